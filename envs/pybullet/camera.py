"""RMB's PyBullet cameras: orbit-style specs, RGB + metric depth, and OpenCV poses.

RMB's TACTO envs describe a camera by an orbit around a target (``RMB: envs/tacto/
TactoSawyerEnvBase.py:20-82,231-239``) and report only its ``fovy`` (principal point centred,
square pixels), so :func:`opencv_pose` plus ``rmb_lerobot.pointcloud.camera_intrinsics`` are
all a point cloud needs.

Example:
    >>> from rmb_lerobot.envs.pybullet.camera import FRONT_CAMERA, opencv_pose, render
    >>> rgb, depth = render(client, FRONT_CAMERA, 640, 480, depth=True)
    >>> world_from_camera = opencv_pose(FRONT_CAMERA)
"""

from __future__ import annotations

import array
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import pybullet as p

from rmb_lerobot.envs.pybullet.client import PybulletClient
from rmb_lerobot.pointcloud import opencv_camera_pose

# RMB: ``shadow=1, lightDirection=[1, 1, 1]`` on every camera image.
_LIGHT_DIRECTION = (1.0, 1.0, 1.0)
_UP_AXIS_Z = 2


@dataclass(frozen=True)
class CameraSpec:
    """A camera orbiting ``target``, as ``computeViewMatrixFromYawPitchRoll`` takes it (z up).

    Attributes:
        name: Image key stem, e.g. ``"front"`` (RMB's ``front_rgb_image``).
        target: World point (x, y, z) in metres the camera looks at.
        distance: Metres from the camera to ``target``.
        yaw: Degrees about world z (90 puts the camera on the +x side of the target,
            looking along -x, back at the robot).
        pitch: Degrees of elevation (negative looks down).
        roll: Degrees about the optical axis.
        fovy: Vertical field of view in degrees (RMB 60); the only intrinsic RMB stores.
        near: Near clip plane in metres (RMB 0.01).
        far: Far clip plane in metres (RMB 100); background pixels read as this depth.
    """

    name: str
    target: tuple[float, float, float]
    distance: float
    yaw: float
    pitch: float
    roll: float = 0.0
    fovy: float = 60.0
    near: float = 0.01
    far: float = 100.0

    def __post_init__(self) -> None:
        target = tuple(float(v) for v in np.asarray(self.target, dtype=np.float64).ravel())
        if len(target) != 3 or not all(math.isfinite(v) for v in target):
            raise ValueError(f"target must be 3 finite numbers, got {self.target!r}")
        object.__setattr__(self, "target", target)
        if not self.distance > 0:
            raise ValueError(f"distance must be positive, got {self.distance!r}")
        if not 0 < self.fovy < 180:
            raise ValueError(f"fovy must be in (0, 180) degrees, got {self.fovy!r}")
        if not 0 < self.near < self.far:
            raise ValueError(f"need 0 < near < far, got near={self.near!r}, far={self.far!r}")

    def view_matrix(self) -> list[float]:
        """PyBullet's 16-float view matrix (column-major, OpenGL camera: y up, looks along -z)."""
        return list(
            p.computeViewMatrixFromYawPitchRoll(
                cameraTargetPosition=self.target,
                distance=self.distance,
                yaw=self.yaw,
                pitch=self.pitch,
                roll=self.roll,
                upAxisIndex=_UP_AXIS_Z,
            )
        )

    def projection_matrix(self, width: int, height: int) -> list[float]:
        """PyBullet's 16-float projection matrix for a ``width`` x ``height`` image."""
        return list(
            p.computeProjectionMatrixFOV(
                fov=self.fovy, aspect=width / height, nearVal=self.near, farVal=self.far
            )
        )


FRONT_CAMERA = CameraSpec("front", target=(0.5, 0.0, 0.05), distance=0.4, yaw=90.0, pitch=-30.0)
"""RMB's "front" camera of the TACTO Sawyer Grasp and Insert envs (640x480 there)."""

SPOON_FRONT_CAMERA = CameraSpec(
    "front", target=(0.8, 0.0, 0.05), distance=1.0, yaw=90.0, pitch=-30.0
)
"""The Spoon env's own "front" camera: further back, to see all three boxes."""


class CameraImages(NamedTuple):
    """What :func:`render_images` returns; fields not asked for are ``None``.

    Attributes:
        rgb: (H, W, 3) uint8.
        depth: (H, W) float32 metres along the optical axis (``far`` where nothing is hit).
        segmentation: (H, W) int32 body unique id per pixel, -1 for background.
    """

    rgb: np.ndarray | None
    depth: np.ndarray | None
    segmentation: np.ndarray | None


def linearize_depth(buffer: np.ndarray, near: float, far: float) -> np.ndarray:
    """OpenGL depth-buffer values in [0, 1] -> float32 metres along the optical axis.

    RMB's formula (``TactoSawyerEnvBase.py`` ``Camera``): ``2nf / (f + n - (2d - 1)(f - n))``,
    computed in float64 so the near/far ratio of 1e4 costs no precision.
    """
    d = np.asarray(buffer, dtype=np.float64)
    metres = 2.0 * near * far / (far + near - (2.0 * d - 1.0) * (far - near))
    return metres.astype(np.float32)


def _check_size(width: int, height: int) -> None:
    for label, value in (("width", width), ("height", height)):
        if isinstance(value, bool) or not isinstance(value, int | np.integer) or value <= 0:
            raise ValueError(f"{label} must be a positive integer number of pixels, got {value!r}")


def render_images(
    client: PybulletClient,
    spec: CameraSpec,
    width: int,
    height: int,
    *,
    rgb: bool = True,
    depth: bool = False,
    segmentation: bool = False,
    shadow: bool = True,
) -> CameraImages:
    """Render one camera image through the client's renderer; see :func:`render`.

    Args:
        client: An open client; its ``renderer`` picks ``ER_BULLET_HARDWARE_OPENGL`` (EGL
            plugin loaded) or ``ER_TINY_RENDERER``.
        spec: The camera.
        width: Image width in pixels.
        height: Image height in pixels.
        rgb: Return the colour image.
        depth: Return metric depth.
        segmentation: Return the per-pixel body id (skipped, via ``ER_NO_SEGMENTATION_MASK``,
            when not asked for).
        shadow: RMB's ``shadow=1``; ignored without ``rgb``, since shadows change only
            colours and TinyRenderer draws the scene a second time for them.

    Returns:
        :class:`CameraImages` with the requested fields set and the others ``None``.

    Raises:
        ValueError: Bad image size, or nothing requested.
        RuntimeError: The client is closed, or uses EGL and this is not its thread.
    """
    _check_size(width, height)
    if not (rgb or depth or segmentation):
        raise ValueError("request at least one of rgb, depth, segmentation")
    if client.closed:
        raise RuntimeError(f"PyBullet client {client.client_id} is closed")
    client.check_render_thread()
    engine = p.ER_BULLET_HARDWARE_OPENGL if client.renderer == "egl" else p.ER_TINY_RENDERER
    _, _, rgba, depth_buffer, seg = p.getCameraImage(
        width,
        height,
        viewMatrix=spec.view_matrix(),
        projectionMatrix=spec.projection_matrix(width, height),
        shadow=int(shadow and rgb),
        lightDirection=_LIGHT_DIRECTION,
        renderer=engine,
        flags=0 if segmentation else p.ER_NO_SEGMENTATION_MASK,
        physicsClientId=client.client_id,
    )
    shape = (height, width)
    metres = None
    if depth:
        metres = linearize_depth(_to_array(depth_buffer, "d", shape), spec.near, spec.far)
    return CameraImages(
        rgb=_rgb(rgba, shape) if rgb else None,
        depth=metres,
        segmentation=_to_array(seg, "i", shape) if segmentation else None,
    )


def _to_array(
    values: Sequence[float] | np.ndarray, code: str, shape: tuple[int, ...]
) -> np.ndarray:
    """One of ``getCameraImage``'s outputs as an array of ``shape``.

    A pybullet built without numpy (``p.isNumpyEnabled() == 0``, as uv's isolated sdist build
    makes it) returns flat tuples of Python numbers; ``array.array`` / ``bytes`` convert those
    in C, 4x faster than ``np.asarray`` (measured at 640x480: RGBA 13 ms vs 53 ms, depth
    7 ms vs 12 ms).

    Args:
        values: A numpy array (numpy-enabled build) or a flat sequence.
        code: ``array`` type code: ``"B"`` uint8, ``"d"`` float64, ``"i"`` int32.
        shape: The shape to return.

    Returns:
        An array of ``shape`` and ``code``'s dtype.
    """
    if isinstance(values, np.ndarray):
        return np.asarray(values, dtype=np.dtype(code)).reshape(shape)
    flat = bytes(values) if code == "B" else array.array(code, values)
    return np.frombuffer(flat, dtype=np.dtype(code)).reshape(shape)


def _rgb(rgba: Sequence[int] | np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """PyBullet's RGBA pixels -> (H, W, 3) uint8, contiguous and writeable."""
    pixels = _to_array(rgba, "B", (*shape, 4))
    return np.array(pixels[:, :, :3], dtype=np.uint8, order="C")


def render(
    client: PybulletClient,
    spec: CameraSpec,
    width: int,
    height: int,
    *,
    rgb: bool = True,
    depth: bool = False,
    shadow: bool = True,
) -> tuple[np.ndarray | None, np.ndarray | None]:
    """RGB and/or metric depth as RMB's TACTO envs record them.

    Measured, RMB's "front" camera at 640x480 over a floor and a cube, median of 20 frames,
    RGB + depth / depth only:

    ============================================  ================  ================
    machine, pybullet build                       EGL               TinyRenderer
    ============================================  ================  ================
    H200 + 16 cores, NVIDIA EGL, numpy build      8.8 / 11 ms       159 / 91 ms
    H200 + 16 cores, NVIDIA EGL, no-numpy build   111 / 76 ms       221 / 148 ms
    2 cores (loaded), llvmpipe, numpy build       95 / 89 ms        349 / 198 ms
    2 cores (loaded), llvmpipe, no-numpy build    340 / 330 ms      550 / 380 ms
    ============================================  ================  ================

    uv's isolated sdist build of pybullet has no numpy (``p.isNumpyEnabled() == 0``), so
    ``getCameraImage`` builds 1.8 M Python numbers per 640x480 frame: that, not drawing,
    dominates unless pybullet is built with numpy importable.

    Args:
        client: An open client from :func:`rmb_lerobot.envs.pybullet.client.connect`.
        spec: The camera.
        width: Image width in pixels (RMB 640).
        height: Image height in pixels (RMB 480).
        rgb: Return the colour image.
        depth: Return depth in metres, linearised as RMB does.
        shadow: RMB's ``shadow=1`` (only affects ``rgb``).

    Returns:
        ``(rgb, depth)``: (H, W, 3) uint8 or ``None``, (H, W) float32 metres or ``None``.
        Don't compare pixels across renderers or machines: EGL and TinyRenderer shade
        differently.

    Raises:
        ValueError: Bad image size, or neither ``rgb`` nor ``depth`` requested.
        RuntimeError: The client is closed, or uses EGL and this is not its thread.
    """
    images = render_images(client, spec, width, height, rgb=rgb, depth=depth, shadow=shadow)
    return images.rgb, images.depth


def opencv_pose(spec: CameraSpec) -> np.ndarray:
    """4x4 world-from-camera pose in OpenCV axes (x right, y down, z forward).

    PyBullet's view matrix is camera-from-world in OpenGL axes (x right, y up, looking along
    -z): the same camera frame as MuJoCo's, so after inverting it the conversion is
    ``rmb_lerobot.pointcloud.opencv_camera_pose``'s.

    Args:
        spec: The camera.

    Returns:
        (4, 4) float64. With ``camera_intrinsics(W, H, spec.fovy)`` (pinhole, principal point
        centred) it maps ``depth_to_points(depth, spec.fovy)`` output to world points
        (checked in the tests: plane pixels land on z = 0 within 3 mm).
    """
    camera_from_world = np.asarray(spec.view_matrix(), dtype=np.float64).reshape(4, 4).T
    rotation = camera_from_world[:3, :3].T  # world-from-camera, OpenGL axes
    position = -rotation @ camera_from_world[:3, 3]
    return opencv_camera_pose(position, rotation)
