"""Depth images to point clouds, the input 3D Diffusion Policy (DP3) needs.

RMB records, per camera, a z-depth image in metres (what MuJoCo renders) plus only the
vertical field of view ``fovy`` in degrees.  From that we assume an ideal pinhole camera:
square pixels, focal length ``f = 0.5 * H / tan(fovy / 2)`` on both axes, and the principal
point at ``(cx, cy) = (W / 2, H / 2)`` -- the same intrinsics RMB passes to Open3D
(``PinholeCameraIntrinsic(width, height, f, f, width / 2, height / 2)``) and uses in its own
``convert_depth_image_to_point_cloud``, so clouds built here line up with RMB's.

Camera frame (OpenCV / pinhole convention), used by every function here::

    x right, y down, z forward along the optical axis (z is the stored depth);
    pixel (row v, column u) with depth z  ->  x = (u - cx) * z / f,  y = (v - cy) * z / f.

Note that MuJoCo's own camera frame looks down -z with y up; the rotation between the two
is ``diag(1, -1, -1)`` and belongs in the camera pose you pass to :func:`transform_points`.

The pipeline is ``depth_to_points -> transform_points -> crop_points ->
farthest_point_sample``; :func:`depth_to_pointcloud` runs it in one call.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

try:
    import fpsample
except ImportError:  # pragma: no cover - fpsample is a declared dependency
    fpsample = None

__all__ = [
    "camera_intrinsics",
    "crop_points",
    "depth_to_pointcloud",
    "depth_to_points",
    "farthest_point_indices",
    "farthest_point_sample",
    "transform_points",
]


# --------------------------------------------------------------------------- validation


def _check_fovy(fovy: Any) -> float:
    """Return ``fovy`` as a float, or raise: a bad fovy gives silently wrong geometry."""
    if np.ndim(fovy) != 0:
        raise ValueError(f"fovy must be a scalar angle in degrees, got shape {np.shape(fovy)}")
    try:
        value = float(fovy)
    except (TypeError, ValueError):
        raise ValueError(f"fovy must be a number of degrees, got {fovy!r}") from None
    if not (math.isfinite(value) and 0.0 < value < 180.0):
        raise ValueError(f"fovy must be in (0, 180) degrees, got {fovy!r}")
    return value


def _check_points(points: ArrayLike, name: str = "points") -> np.ndarray:
    arr = np.asarray(points)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ValueError(f"{name} must have shape (N, 3), got {arr.shape}")
    return arr


def _check_colors(colors: ArrayLike | None, n_points: int) -> np.ndarray | None:
    if colors is None:
        return None
    arr = np.asarray(colors)
    if arr.shape != (n_points, 3):
        raise ValueError(f"colors must have shape ({n_points}, 3) to match points, got {arr.shape}")
    return arr


def _check_vector3(value: ArrayLike, name: str) -> np.ndarray:
    """A length-3 float vector; a scalar is broadcast to all three axes."""
    arr = np.asarray(value, dtype=np.float64)
    if arr.ndim == 0:
        arr = np.full(3, float(arr))
    if arr.shape != (3,):
        raise ValueError(f"{name} must be a scalar or have shape (3,), got {arr.shape}")
    if np.isnan(arr).any():
        raise ValueError(f"{name} must not contain NaN, got {arr.tolist()}")
    return arr


def _float_dtype(arr: np.ndarray) -> np.dtype:
    return arr.dtype if np.issubdtype(arr.dtype, np.floating) else np.dtype(np.float64)


# --------------------------------------------------------------------------- intrinsics


def camera_intrinsics(width: int, height: int, fovy_deg: float) -> np.ndarray:
    """Pinhole matrix ``K`` (3, 3, float64) for an RMB camera known only by its ``fovy``.

    ``K = [[f, 0, W/2], [0, f, H/2], [0, 0, 1]]`` with ``f = 0.5 * H / tan(fovy / 2)``: one
    definition shared by every caller so that back-projection and projection agree.
    """
    for name, value in (("width", width), ("height", height)):
        if isinstance(value, bool) or not isinstance(value, int | np.integer) or value <= 0:
            raise ValueError(f"{name} must be a positive integer number of pixels, got {value!r}")
    fovy = _check_fovy(fovy_deg)
    f = 0.5 * height / math.tan(math.radians(fovy) / 2.0)
    return np.array(
        [[f, 0.0, width / 2.0], [0.0, f, height / 2.0], [0.0, 0.0, 1.0]], dtype=np.float64
    )


# --------------------------------------------------------------------------- back-projection


def depth_to_points(
    depth: ArrayLike,
    fovy: float,
    rgb: ArrayLike | None = None,
    *,
    max_depth: float | None = None,
) -> tuple[np.ndarray, np.ndarray | None]:
    """Back-project a z-depth image (metres) into camera-frame points (x right, y down, z fwd).

    Returns ``(points, colors)``: ``points`` (N, 3) float32 and, if ``rgb`` (H, W, 3) is given,
    ``colors`` (N, 3) float32 in [0, 1] row-aligned with ``points`` (else ``None``).  ``rgb``
    may be uint8 (0-255) or floating (already in [0, 1]).  Pixels whose depth is <= 0,
    non-finite, or > ``max_depth`` carry no surface (MuJoCo writes the far plane or 0 there)
    and are dropped; the rest keep row-major pixel order, so ``points[k]`` comes from the
    k-th valid pixel scanning rows top to bottom.
    """
    depth = np.asarray(depth)
    if depth.ndim != 2:
        raise ValueError(f"depth must be a 2-D (H, W) image, got shape {depth.shape}")
    if not np.issubdtype(depth.dtype, np.floating):
        raise ValueError(
            f"depth must be a floating-point image in metres, got dtype {depth.dtype} "
            "(convert integer millimetres with depth / 1000.0 first)"
        )
    if depth.size == 0:
        raise ValueError(f"depth must not be empty, got shape {depth.shape}")
    height, width = depth.shape
    k = camera_intrinsics(width, height, fovy)

    colors_img = None
    if rgb is not None:
        rgb = np.asarray(rgb)
        if rgb.shape != (height, width, 3):
            raise ValueError(
                f"rgb must have shape (H, W, 3) = {(height, width, 3)} to match depth, "
                f"got {rgb.shape}"
            )
        if not (rgb.dtype == np.uint8 or np.issubdtype(rgb.dtype, np.floating)):
            raise ValueError(f"rgb must be uint8 or floating in [0, 1], got dtype {rgb.dtype}")
        colors_img = rgb

    valid = np.isfinite(depth) & (depth > 0)
    if max_depth is not None:
        max_depth = float(max_depth)
        if not max_depth > 0:
            raise ValueError(f"max_depth must be positive, got {max_depth!r}")
        valid &= depth <= max_depth

    v, u = np.nonzero(valid)  # row-major order, same as depth.ravel()
    z = depth[v, u].astype(np.float64)
    f, cx, cy = k[0, 0], k[0, 2], k[1, 2]
    points = np.empty((z.shape[0], 3), dtype=np.float32)
    points[:, 0] = (u - cx) * z / f
    points[:, 1] = (v - cy) * z / f
    points[:, 2] = z

    colors = None
    if colors_img is not None:
        picked = colors_img[v, u]
        if picked.dtype == np.uint8:
            colors = picked.astype(np.float32) / np.float32(255.0)
        else:
            colors = picked.astype(np.float32)
    return points, colors


# --------------------------------------------------------------------------- geometry


def transform_points(
    points: ArrayLike,
    rotation: ArrayLike | None = None,
    translation: ArrayLike | None = None,
    *,
    matrix: ArrayLike | None = None,
) -> np.ndarray:
    """Map points to another frame: ``p' = R @ p + t`` (e.g. camera -> world with the camera pose).

    Give either ``rotation`` (3, 3) and/or ``translation`` (3,), or a homogeneous ``matrix``
    (4, 4) whose last row is ``[0, 0, 0, 1]``.  The result keeps the input's float dtype
    (float64 for integer input); the arithmetic is done in float64.
    """
    pts = _check_points(points)
    out_dtype = _float_dtype(pts)
    if matrix is not None:
        if rotation is not None or translation is not None:
            raise ValueError("pass either matrix or rotation/translation, not both")
        m = np.asarray(matrix, dtype=np.float64)
        if m.shape != (4, 4):
            raise ValueError(f"matrix must have shape (4, 4), got {m.shape}")
        if not np.allclose(m[3], [0.0, 0.0, 0.0, 1.0]):
            raise ValueError(f"matrix must have last row [0, 0, 0, 1], got {m[3].tolist()}")
        rotation, translation = m[:3, :3], m[:3, 3]

    out = pts.astype(np.float64)
    if rotation is not None:
        r = np.asarray(rotation, dtype=np.float64)
        if r.shape != (3, 3):
            raise ValueError(f"rotation must have shape (3, 3), got {r.shape}")
        out = out @ r.T
    if translation is not None:
        t = np.asarray(translation, dtype=np.float64)
        if t.shape != (3,):
            raise ValueError(f"translation must have shape (3,), got {t.shape}")
        out = out + t
    return out.astype(out_dtype, copy=False)


def crop_points(
    points: ArrayLike,
    colors: ArrayLike | None = None,
    *,
    min_bound: ArrayLike | None = None,
    max_bound: ArrayLike | None = None,
) -> tuple[np.ndarray, np.ndarray | None]:
    """Keep points inside the axis-aligned box ``min_bound <= p <= max_bound`` (inclusive).

    Cropping to the workspace removes table/background points before sampling, so the fixed
    point budget is spent on the scene that matters.  Either bound may be ``None``
    (unbounded on that side) or a scalar (same on all axes).  Returns ``(points, colors)``
    with ``colors`` filtered by the same mask (``None`` if not given).  RMB's own
    ``crop_pointcloud_bb`` uses strict inequalities; the two differ only for points lying
    exactly on a face of the box.
    """
    pts = _check_points(points)
    cols = _check_colors(colors, pts.shape[0])
    lo = None if min_bound is None else _check_vector3(min_bound, "min_bound")
    hi = None if max_bound is None else _check_vector3(max_bound, "max_bound")
    if lo is not None and hi is not None and (lo > hi).any():
        raise ValueError(
            f"min_bound must be <= max_bound on every axis, got {lo.tolist()} > {hi.tolist()}"
        )
    mask = np.ones(pts.shape[0], dtype=bool)
    if lo is not None:
        mask &= np.all(pts >= lo, axis=1)
    if hi is not None:
        mask &= np.all(pts <= hi, axis=1)
    return pts[mask], None if cols is None else cols[mask]


# --------------------------------------------------------------------------- sampling


def _fps_numpy(points: np.ndarray, n_samples: int, start: int) -> np.ndarray:
    """Plain O(N * n) farthest-point sampling; used only when ``fpsample`` is unavailable."""
    pts = points.astype(np.float64)
    order = np.empty(n_samples, dtype=np.int64)
    order[0] = start
    dist = np.sum((pts - pts[start]) ** 2, axis=1)
    for i in range(1, n_samples):
        nxt = int(np.argmax(dist))
        order[i] = nxt
        np.minimum(dist, np.sum((pts - pts[nxt]) ** 2, axis=1), out=dist)
    return order


def farthest_point_indices(
    points: ArrayLike,
    n: int,
    seed: int | None = None,
    *,
    start_index: int | None = None,
) -> np.ndarray:
    """Indices (n,) int64 of a farthest-point sample of ``points``; see farthest_point_sample."""
    pts = _check_points(points)
    if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
        raise ValueError(f"n must be a positive integer number of points, got {n!r}")
    n = int(n)
    n_pts = pts.shape[0]
    if n_pts == 0:
        raise ValueError(
            "points is empty: nothing to sample (all pixels invalid, beyond max_depth, "
            "or cropped away?)"
        )
    if not np.isfinite(pts).all():
        raise ValueError("points must be finite for farthest-point sampling")
    if seed is not None and start_index is not None:
        raise ValueError("pass either seed or start_index, not both")

    if start_index is not None:
        if (
            isinstance(start_index, bool)
            or not isinstance(start_index, int | np.integer)
            or not 0 <= start_index < n_pts
        ):
            raise ValueError(f"start_index must be an integer in [0, {n_pts}), got {start_index!r}")
        start = int(start_index)
    elif seed is not None:
        start = int(np.random.default_rng(seed).integers(n_pts))
    else:
        start = 0

    k = min(n, n_pts)
    pts32 = np.ascontiguousarray(pts, dtype=np.float32)
    if fpsample is None:
        order = _fps_numpy(pts32, k, start)
    elif start_index is not None:
        # The bucket variant maps start_idx through its internal KD-tree ordering, so only
        # the vanilla algorithm guarantees that points[start_index] is the first sample.
        order = fpsample.fps_sampling(pts32, k, start_idx=start)
    else:
        order = fpsample.bucket_fps_kdtree_sampling(pts32, k, start_idx=start)
    order = np.asarray(order, dtype=np.int64)
    if k < n:
        order = np.resize(order, n)  # cycle through all points: each repeated ~n / N times
    return order


def farthest_point_sample(
    points: ArrayLike,
    n: int,
    colors: ArrayLike | None = None,
    seed: int | None = None,
    *,
    start_index: int | None = None,
) -> tuple[np.ndarray, np.ndarray | None]:
    """Down-sample to exactly ``n`` well-spread points by farthest-point sampling (FPS).

    FPS keeps thin structures (gripper fingers, handles) that uniform random sampling would
    thin out.  Uses ``fpsample``'s bucket/KD-tree algorithm ("QuickFPS"), falling back to
    its vanilla algorithm when an exact ``start_index`` is requested and to a NumPy loop if
    ``fpsample`` is not installed.  Returns ``(points, colors)`` row-aligned, ``colors``
    ``None`` if not given.

    * **Fixed size**: DP3 needs a fixed N, so with fewer than ``n`` input points every point
      is kept and the sample is padded by repeating them cyclically (in FPS order) up to n.
    * **Deterministic**: ``seed=None`` starts from index 0 (like pytorch3d's default used by
      RMB/DP3); an integer ``seed`` picks the start index from ``np.random.default_rng(seed)``.
      With the bucket algorithm, the start index is taken through fpsample's KD-tree
      ordering, so the first sample is fixed by it but is not necessarily
      ``points[start]``; pass ``start_index`` to force the first sample to be that point.
    """
    pts = _check_points(points)
    cols = _check_colors(colors, pts.shape[0])
    idx = farthest_point_indices(pts, n, seed, start_index=start_index)
    return pts[idx], None if cols is None else cols[idx]


# --------------------------------------------------------------------------- one call


MUJOCO_TO_OPENCV = np.diag([1.0, -1.0, -1.0])  # MuJoCo camera axes (y up, looks along -z)


def checked_camera_pose(pose: Any, name: str) -> list[list[float]]:
    """A 4x4 rigid world-from-camera transform as nested lists, or ValueError naming ``name`` and
    the value: what DP3 configs and ``rmb-convert`` accept for ``<camera>_depth_image_pose``."""
    try:
        matrix = np.asarray(pose, dtype=np.float64)
    except (TypeError, ValueError):
        matrix = np.full(1, np.nan)
    if matrix.shape != (4, 4) or not np.isfinite(matrix).all():
        raise ValueError(f"{name} must be a finite 4x4 matrix (world from camera), got {pose!r}")
    rotation = matrix[:3, :3]
    if not np.allclose(matrix[3], [0, 0, 0, 1]) or not np.allclose(
        rotation @ rotation.T, np.eye(3), atol=1e-5
    ):
        raise ValueError(
            f"{name} must be a rigid transform (orthonormal rotation, last row 0 0 0 1), "
            f"got {matrix.tolist()}"
        )
    return matrix.tolist()


def opencv_camera_pose(position: ArrayLike, rotation: ArrayLike) -> np.ndarray:
    """4x4 world-from-camera pose in OpenCV axes from a MuJoCo camera's world pose.

    ``position`` (3,) and ``rotation`` (3, 3) (or its 9 row-major entries) are MuJoCo's
    ``data.cam_xpos`` / ``data.cam_xmat`` rows: the camera frame with y up, looking along -z.
    The result maps points of :func:`depth_to_points` (x right, y down, z forward) to the world
    with :func:`transform_points` (``matrix=``).
    """
    pos = _check_vector3(position, "position")
    rot = np.asarray(rotation, dtype=np.float64).reshape(3, 3)
    pose = np.eye(4)
    pose[:3, :3] = rot @ MUJOCO_TO_OPENCV
    pose[:3, 3] = pos
    return pose


def depth_to_pointcloud(
    depth: ArrayLike,
    fovy: float,
    rgb: ArrayLike | None = None,
    *,
    transform: ArrayLike | None = None,
    min_bound: ArrayLike | None = None,
    max_bound: ArrayLike | None = None,
    num_points: int | None = None,
    max_depth: float | None = None,
    seed: int | None = None,
) -> np.ndarray:
    """Depth (+ RGB) image -> the fixed-size point cloud 3D Diffusion Policy consumes.

    Runs :func:`depth_to_points` (dropping invalid / > ``max_depth`` pixels), then
    :func:`transform_points` with the 4x4 ``transform`` (e.g. the camera-to-world pose, in
    the x-right / y-down / z-forward camera convention), then :func:`crop_points` with the
    bounds (expressed in the transformed frame), then :func:`farthest_point_sample` to
    ``num_points`` (padding if fewer remain).  Steps whose arguments are ``None`` are skipped.

    Returns one float32 array: (N, 3) ``xyz``, or (N, 6) ``xyz + rgb`` in [0, 1] when ``rgb``
    is given -- DP3's ``point_cloud`` layout.
    """
    points, colors = depth_to_points(depth, fovy, rgb, max_depth=max_depth)
    if transform is not None:
        points = transform_points(points, matrix=transform)
    if min_bound is not None or max_bound is not None:
        points, colors = crop_points(points, colors, min_bound=min_bound, max_bound=max_bound)
    if num_points is not None:
        points, colors = farthest_point_sample(points, num_points, colors, seed)
    if colors is None:
        return np.ascontiguousarray(points, dtype=np.float32)
    return np.concatenate([points, colors], axis=1).astype(np.float32, copy=False)
