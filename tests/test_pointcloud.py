"""Depth -> point cloud utilities, checked against hand-computed pinhole geometry.

Camera frame throughout: x right, y down, z forward; f = 0.5 * H / tan(fovy / 2) and the
principal point is (W / 2, H / 2), as in RMB.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rmb_lerobot import pointcloud
from rmb_lerobot.pointcloud import (
    camera_intrinsics,
    crop_points,
    depth_to_pointcloud,
    depth_to_points,
    farthest_point_indices,
    farthest_point_sample,
    opencv_camera_pose,
    transform_points,
)

# A 4 x 6 image with fovy = 90 deg: tan(45 deg) = 1, so f = 0.5 * 4 = 2, cx = 3, cy = 2.
H, W, FOVY = 4, 6, 90.0


def plane(depth: float = 2.0, height: int = H, width: int = W) -> np.ndarray:
    return np.full((height, width), depth, dtype=np.float32)


def pixel_index_rgb(height: int = H, width: int = W) -> np.ndarray:
    """RGB image whose red = row and green = column, so a colour tells where it came from."""
    rgb = np.zeros((height, width, 3), dtype=np.uint8)
    rgb[..., 0] = np.arange(height)[:, None]
    rgb[..., 1] = np.arange(width)[None, :]
    rgb[..., 2] = 255
    return rgb


# --------------------------------------------------------------------------- intrinsics


def test_camera_intrinsics_from_fovy():
    k = camera_intrinsics(640, 480, 90.0)
    np.testing.assert_allclose(k, [[240, 0, 320], [0, 240, 240], [0, 0, 1]])

    # fovy = 60 deg: f = 240 / tan(30 deg) = 240 * sqrt(3)
    k60 = camera_intrinsics(640, 480, 60.0)
    assert k60[0, 0] == pytest.approx(240 * math.sqrt(3))
    assert k60[1, 1] == k60[0, 0]  # square pixels


@pytest.mark.parametrize("fovy", [0.0, 180.0, -10.0, float("nan"), float("inf")])
def test_camera_intrinsics_rejects_bad_fovy(fovy):
    with pytest.raises(ValueError, match="fovy"):
        camera_intrinsics(640, 480, fovy)


def test_camera_intrinsics_rejects_bad_size():
    with pytest.raises(ValueError, match="width"):
        camera_intrinsics(0, 480, 45.0)
    with pytest.raises(ValueError, match="height"):
        camera_intrinsics(640, 48.5, 45.0)


# --------------------------------------------------------------------------- back-projection


def test_constant_plane_corners_by_hand():
    points, colors = depth_to_points(plane(2.0), FOVY)

    assert colors is None
    assert points.dtype == np.float32
    assert points.shape == (H * W, 3)
    np.testing.assert_allclose(points[:, 2], 2.0)

    # Row-major order: index = row * W + col.  x = (col - 3) * 2 / 2, y = (row - 2) * 2 / 2.
    top_left, top_right = points[0], points[W - 1]
    bottom_left, bottom_right = points[(H - 1) * W], points[-1]
    np.testing.assert_allclose(top_left, [-3.0, -2.0, 2.0])
    np.testing.assert_allclose(top_right, [2.0, -2.0, 2.0])
    np.testing.assert_allclose(bottom_left, [-3.0, 1.0, 2.0])
    np.testing.assert_allclose(bottom_right, [2.0, 1.0, 2.0])


def test_centre_pixel_is_on_the_optical_axis():
    depth = plane(0.75, height=480, width=640)
    points, _ = depth_to_points(depth, 45.0)

    centre = points[240 * 640 + 320]  # pixel (row H/2, col W/2) = principal point
    np.testing.assert_allclose(centre, [0.0, 0.0, 0.75], atol=1e-7)


def test_top_edge_lies_on_the_half_fovy_ray():
    depth = plane(1.5, height=480, width=640)
    points, _ = depth_to_points(depth, 60.0)

    top_centre = points[0 * 640 + 320]  # row 0 is H/2 pixels above the principal point
    assert top_centre[1] == pytest.approx(-1.5 * math.tan(math.radians(30.0)), rel=1e-6)
    assert top_centre[0] == pytest.approx(0.0, abs=1e-7)


def test_invalid_and_far_pixels_are_dropped():
    depth = plane(2.0)
    depth[0, 0] = 0.0  # no return
    depth[0, 1] = -1.0
    depth[1, 2] = np.nan
    depth[2, 3] = np.inf
    depth[3, 5] = 9.0  # far background, removed by max_depth

    points, _ = depth_to_points(depth, FOVY)
    assert len(points) == H * W - 4  # only the 9 m pixel survives without max_depth
    assert np.isfinite(points).all()

    points, _ = depth_to_points(depth, FOVY, max_depth=5.0)
    assert len(points) == H * W - 5
    np.testing.assert_allclose(points[:, 2], 2.0)
    np.testing.assert_allclose(points[0], [-1.0, -2.0, 2.0])  # first survivor: pixel (0, 2)


def test_colors_stay_aligned_with_points():
    depth = plane(2.0)
    depth[0, :3] = 0.0  # drop some pixels so alignment is actually exercised
    rgb = pixel_index_rgb()

    points, colors = depth_to_points(depth, FOVY, rgb)

    assert colors.dtype == np.float32
    assert colors.shape == points.shape
    assert colors.min() >= 0.0 and colors.max() <= 1.0
    np.testing.assert_allclose(colors[:, 2], 1.0)  # blue 255 -> 1.0
    # Recover each point's pixel from its colour and check it against the geometry.
    row = np.rint(colors[:, 0] * 255)
    col = np.rint(colors[:, 1] * 255)
    np.testing.assert_allclose(points[:, 0], (col - 3) * 2.0 / 2.0)
    np.testing.assert_allclose(points[:, 1], (row - 2) * 2.0 / 2.0)


def test_float_rgb_in_unit_range_is_passed_through():
    rgb = np.full((H, W, 3), 0.25, dtype=np.float64)
    _, colors = depth_to_points(plane(), FOVY, rgb)
    np.testing.assert_allclose(colors, 0.25)


def test_depth_to_points_names_the_bad_argument():
    with pytest.raises(ValueError, match="depth"):
        depth_to_points(np.ones((2, 3, 1), dtype=np.float32), FOVY)
    with pytest.raises(ValueError, match="depth"):
        depth_to_points(np.ones((2, 3), dtype=np.uint16), FOVY)  # millimetres, not metres
    with pytest.raises(ValueError, match="rgb"):
        depth_to_points(plane(), FOVY, np.zeros((H, W + 1, 3), dtype=np.uint8))
    with pytest.raises(ValueError, match="rgb"):
        depth_to_points(plane(), FOVY, np.zeros((H, W, 4), dtype=np.uint8))
    with pytest.raises(ValueError, match="fovy"):
        depth_to_points(plane(), 180.0)
    with pytest.raises(ValueError, match="max_depth"):
        depth_to_points(plane(), FOVY, max_depth=0.0)


# --------------------------------------------------------------------------- transform

# 90 deg about +z: x -> y, y -> -x.
ROT_Z_90 = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])


def test_rotate_90_degrees_about_z():
    points = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 2.0, 3.0]], dtype=np.float32)

    rotated = transform_points(points, ROT_Z_90)

    assert rotated.dtype == np.float32
    np.testing.assert_allclose(rotated, [[0, 1, 0], [-1, 0, 0], [-2, 1, 3]], atol=1e-7)


def test_rotation_and_translation_equal_the_4x4_matrix():
    points = np.random.default_rng(0).normal(size=(10, 3))
    t = np.array([0.5, -1.0, 2.0])
    matrix = np.eye(4)
    matrix[:3, :3], matrix[:3, 3] = ROT_Z_90, t

    np.testing.assert_allclose(
        transform_points(points, ROT_Z_90, t), transform_points(points, matrix=matrix)
    )
    np.testing.assert_allclose(transform_points(points, translation=t), points + t)
    np.testing.assert_allclose(transform_points(points), points)


def test_opencv_camera_pose_from_a_mujoco_camera():
    """A MuJoCo camera 1 m up with the identity orientation looks straight down (its -z): the
    centre pixel at depth 1 is the world origin, image right is world x, image down world -y."""
    pose = opencv_camera_pose([0.0, 0.0, 1.0], np.eye(3).ravel())
    points, _ = depth_to_points(plane(1.0, 4, 4), 90.0)  # principal point: pixel (2, 2)
    world = transform_points(points, matrix=pose)
    np.testing.assert_allclose(world[10], [0, 0, 0], atol=1e-7)
    assert world[11, 0] > 0 and world[14, 1] < 0  # one column right, one row down
    np.testing.assert_allclose(world[:, 2], 0.0, atol=1e-7)  # the plane z = 1 below the camera
    with pytest.raises(ValueError, match="position"):
        opencv_camera_pose([0.0, 1.0], np.eye(3))


def test_transform_points_names_the_bad_argument():
    points = np.zeros((2, 3))
    with pytest.raises(ValueError, match="points"):
        transform_points(np.zeros((2, 4)), ROT_Z_90)
    with pytest.raises(ValueError, match="rotation"):
        transform_points(points, np.eye(4))
    with pytest.raises(ValueError, match="translation"):
        transform_points(points, translation=[1.0, 2.0])
    with pytest.raises(ValueError, match="matrix"):
        transform_points(points, ROT_Z_90, matrix=np.eye(4))
    with pytest.raises(ValueError, match="matrix"):
        transform_points(points, matrix=np.ones((4, 4)))  # not homogeneous


# --------------------------------------------------------------------------- crop


def test_crop_keeps_points_in_the_box_and_their_colors():
    points = np.array(
        [[0.0, 0.0, 0.0], [0.5, 0.5, 0.5], [1.0, 1.0, 1.0], [2.0, 0.0, 0.0], [0.5, -1.0, 0.5]],
        dtype=np.float32,
    )
    colors = np.arange(15, dtype=np.float32).reshape(5, 3) / 15

    kept, kept_colors = crop_points(points, colors, min_bound=[0, 0, 0], max_bound=[1, 1, 1])

    np.testing.assert_array_equal(kept, points[[0, 1, 2]])  # faces are inclusive
    np.testing.assert_array_equal(kept_colors, colors[[0, 1, 2]])


def test_crop_with_one_sided_or_scalar_bounds():
    points = np.array([[0.0, 0.0, 0.1], [0.0, 0.0, 0.9], [5.0, 5.0, 5.0]])

    above_table, colors = crop_points(points, min_bound=[-np.inf, -np.inf, 0.5])
    assert colors is None
    np.testing.assert_array_equal(above_table, points[[1, 2]])

    in_unit_cube, _ = crop_points(points, min_bound=0.0, max_bound=1.0)
    np.testing.assert_array_equal(in_unit_cube, points[[0, 1]])


def test_crop_names_the_bad_argument():
    points = np.zeros((3, 3))
    with pytest.raises(ValueError, match="min_bound"):
        crop_points(points, min_bound=[0, 0])
    with pytest.raises(ValueError, match="min_bound"):
        crop_points(points, min_bound=[1, 1, 1], max_bound=[0, 0, 0])
    with pytest.raises(ValueError, match="colors"):
        crop_points(points, np.zeros((2, 3)), max_bound=1.0)


# --------------------------------------------------------------------------- FPS


def line(n: int = 101) -> np.ndarray:
    """Points evenly spaced on the x axis from 0 to 1."""
    return np.stack([np.linspace(0.0, 1.0, n), np.zeros(n), np.zeros(n)], axis=1)


def test_fps_on_a_line_picks_both_ends():
    sample, _ = farthest_point_sample(line(), 3)

    xs = sorted(sample[:, 0].tolist())
    assert xs[0] == 0.0 and xs[-1] == 1.0


def test_fps_from_a_given_start_index_goes_to_the_far_end_next():
    idx = farthest_point_indices(line(), 3, start_index=0)

    assert idx.tolist() == [0, 100, 50]  # start, far end, then the middle


def test_fps_returns_n_distinct_well_spread_points():
    rng = np.random.default_rng(0)
    points = np.c_[rng.random((2000, 2)), np.full(2000, 2.0)].astype(np.float32)  # table top

    sample, _ = farthest_point_sample(points, 64)

    assert sample.shape == (64, 3)
    assert len(np.unique(sample, axis=0)) == 64

    def covering_radius(subset: np.ndarray) -> float:
        """Largest distance from any input point to its nearest sampled point."""
        d = np.linalg.norm(points[:, None, :] - subset[None, :, :], axis=2)
        return float(d.min(axis=1).max())

    random_subset = points[rng.choice(len(points), 64, replace=False)]
    assert covering_radius(sample) < 0.75 * covering_radius(random_subset)


def test_fps_pads_by_repeating_when_too_few_points():
    points = line(5)
    colors = np.repeat(np.linspace(0.0, 1.0, 5)[:, None], 3, axis=1)

    sample, sample_colors = farthest_point_sample(points, 12, colors)

    assert sample.shape == (12, 3)
    # Every input point is kept, each at least twice (12 // 5), none invented.
    rows, counts = np.unique(sample, axis=0, return_counts=True)
    np.testing.assert_array_equal(rows, points)
    assert counts.min() >= 2
    # Colours travel with their points.
    np.testing.assert_array_equal(sample_colors[:, 0], sample[:, 0])


def test_fps_is_deterministic():
    points = np.random.default_rng(1).random((1000, 3))

    default_a = farthest_point_indices(points, 32)
    default_b = farthest_point_indices(points, 32)
    seeded_a = farthest_point_indices(points, 32, seed=7)
    seeded_b = farthest_point_indices(points, 32, seed=7)
    other_seed = farthest_point_indices(points, 32, seed=8)

    np.testing.assert_array_equal(default_a, default_b)
    np.testing.assert_array_equal(seeded_a, seeded_b)
    assert not np.array_equal(seeded_a, other_seed)
    assert farthest_point_indices(points, 32, start_index=123)[0] == 123


def test_fps_numpy_fallback_matches_fpsample(monkeypatch):
    points = np.random.default_rng(2).random((500, 3))
    expected = farthest_point_indices(points, 40, start_index=17)  # fpsample, exact start

    monkeypatch.setattr(pointcloud, "fpsample", None)  # as if fpsample were not installed
    np.testing.assert_array_equal(farthest_point_indices(points, 40, start_index=17), expected)


def test_fps_names_the_bad_argument():
    with pytest.raises(ValueError, match="n must"):
        farthest_point_sample(line(), 0)
    with pytest.raises(ValueError, match="points is empty"):
        farthest_point_sample(np.zeros((0, 3)), 8)
    with pytest.raises(ValueError, match="colors"):
        farthest_point_sample(line(), 8, np.zeros((3, 3)))
    with pytest.raises(ValueError, match="start_index"):
        farthest_point_indices(line(), 8, start_index=101)


# --------------------------------------------------------------------------- one call


def test_depth_to_pointcloud_for_dp3():
    # A camera 1 m above a table, looking straight down: camera z -> world -z,
    # camera y (down in the image) -> world -y, camera x -> world x.
    camera_to_world = np.eye(4)
    camera_to_world[:3, :3] = np.diag([1.0, -1.0, -1.0])
    camera_to_world[:3, 3] = [0.0, 0.0, 1.0]
    depth = plane(1.0, height=48, width=64)
    depth[:4] = np.inf  # a strip with no return
    rgb = np.full((48, 64, 3), 128, dtype=np.uint8)

    cloud = depth_to_pointcloud(
        depth,
        60.0,
        rgb,
        transform=camera_to_world,
        min_bound=[-0.2, -0.2, -0.01],
        max_bound=[0.2, 0.2, 0.01],
        num_points=256,
    )

    assert cloud.shape == (256, 6)
    assert cloud.dtype == np.float32
    np.testing.assert_allclose(cloud[:, 2], 0.0, atol=1e-6)  # everything on the table
    assert np.abs(cloud[:, :2]).max() <= 0.2
    np.testing.assert_allclose(cloud[:, 3:], 128 / 255)
    assert len(np.unique(cloud[:, :3], axis=0)) == 256


def test_depth_to_pointcloud_without_optional_steps():
    cloud = depth_to_pointcloud(plane(2.0), FOVY)

    points, _ = depth_to_points(plane(2.0), FOVY)
    np.testing.assert_array_equal(cloud, points)  # (N, 3), every valid pixel


def test_depth_to_pointcloud_pads_a_sparse_view():
    depth = np.zeros((H, W), dtype=np.float32)
    depth[1, 1] = depth[2, 4] = 1.0  # only two valid pixels

    cloud = depth_to_pointcloud(depth, FOVY, num_points=8)

    assert cloud.shape == (8, 3)
    assert len(np.unique(cloud, axis=0)) == 2
