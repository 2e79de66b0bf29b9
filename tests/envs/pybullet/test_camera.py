"""RMB's PyBullet cameras: metric depth, fovy and the OpenCV pose agree with known geometry.

The scene is a ground plane at z = 0 and a 0.1 m cube centred on RMB's "front" camera target,
so the optical axis hits the cube's +x face at a distance we can work out by hand.
"""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np
import pybullet as p
import pytest

from rmb_lerobot.envs.pybullet.camera import (
    FRONT_CAMERA,
    SPOON_FRONT_CAMERA,
    CameraSpec,
    linearize_depth,
    opencv_pose,
    render,
    render_images,
)
from rmb_lerobot.envs.pybullet.client import PybulletClient, connect, egl_unavailable_reason
from rmb_lerobot.pointcloud import depth_to_points, transform_points

W, H = 160, 120  # small, so each render takes milliseconds; centre pixel (row 60, col 80)
HALF = 0.05  # cube half-extent, metres
CUBE_CENTRE = FRONT_CAMERA.target  # (0.5, 0, 0.05): the cube rests on the plane


def _build_scene(client: PybulletClient) -> int:
    """Plane at z = 0 plus the cube; returns the cube's body id."""
    client.loadURDF("plane.urdf")
    box = client.createCollisionShape(p.GEOM_BOX, halfExtents=[HALF] * 3)
    visual = client.createVisualShape(p.GEOM_BOX, halfExtents=[HALF] * 3, rgbaColor=[1, 0, 0, 1])
    return client.createMultiBody(0.0, box, visual, basePosition=CUBE_CENTRE)


@pytest.fixture(scope="module", params=["tiny", "egl"])
def scene(request: pytest.FixtureRequest) -> Iterator[tuple[PybulletClient, int]]:
    """One client per renderer with the plane and cube; the EGL one is skipped, with the
    reason, where EGL cannot load (checked only when an EGL test runs)."""
    if request.param == "egl" and (reason := egl_unavailable_reason()) is not None:
        pytest.skip(f"EGL unavailable: {reason}")
    with connect(renderer=request.param) as client:
        assert client.renderer == request.param
        yield client, _build_scene(client)


def _axis_hit_distance(spec: CameraSpec) -> float:
    """Distance along the optical axis from the camera to the cube's +x face (x = 0.55).

    yaw 90 / pitch -30 puts the camera on the +x side of the target, looking along
    (-cos 30, 0, -sin 30); the axis passes through the target, inside the cube.
    """
    forward_x = math.cos(math.radians(spec.pitch))
    camera_x = spec.target[0] + spec.distance * forward_x
    return (camera_x - (CUBE_CENTRE[0] + HALF)) / forward_x


def test_rmb_camera_specs() -> None:
    rmb_front = CameraSpec("front", target=(0.5, 0, 0.05), distance=0.4, yaw=90, pitch=-30)
    assert rmb_front == FRONT_CAMERA
    assert (FRONT_CAMERA.fovy, FRONT_CAMERA.near, FRONT_CAMERA.far, FRONT_CAMERA.roll) == (
        60.0,
        0.01,
        100.0,
        0.0,
    )
    assert SPOON_FRONT_CAMERA.target == (0.8, 0.0, 0.05) and SPOON_FRONT_CAMERA.distance == 1.0


def test_bad_specs_are_refused() -> None:
    with pytest.raises(ValueError, match="target"):
        CameraSpec("x", (0, 0), 1.0, 0, 0)
    with pytest.raises(ValueError, match="near"):
        CameraSpec("x", (0, 0, 0), 1.0, 0, 0, near=1.0, far=0.5)


def test_linearize_depth_end_points() -> None:
    metres = linearize_depth(np.array([0.0, 1.0]), near=0.01, far=100.0)
    assert metres.dtype == np.float32
    np.testing.assert_allclose(metres, [0.01, 100.0], rtol=1e-6)


def test_opencv_pose_sits_at_the_orbit_and_looks_at_the_target() -> None:
    pose = opencv_pose(FRONT_CAMERA)
    np.testing.assert_allclose(pose[:3, :3] @ pose[:3, :3].T, np.eye(3), atol=1e-6)
    position, forward, down = pose[:3, 3], pose[:3, 2], pose[:3, 1]
    s, c = math.sin(math.radians(30)), math.cos(math.radians(30))
    np.testing.assert_allclose(position, [0.5 + 0.4 * c, 0.0, 0.05 + 0.4 * s], atol=1e-6)
    np.testing.assert_allclose(forward, [-c, 0.0, -s], atol=1e-6)
    assert down[2] < 0  # image y points down the world


def test_centre_pixel_depth_is_the_distance_along_the_optical_axis(scene) -> None:
    client, _ = scene
    rgb, depth = render(client, FRONT_CAMERA, W, H, rgb=False, depth=True)
    assert rgb is None and depth.dtype == np.float32 and depth.shape == (H, W)
    expected = _axis_hit_distance(FRONT_CAMERA)  # 0.3423 m
    assert depth[H // 2, W // 2] == pytest.approx(expected, abs=3e-3)


def test_back_projected_pixels_land_on_the_plane_and_the_cube(scene) -> None:
    """Depth linearisation, fovy (pinhole, centred principal point) and pose agree."""
    client, _ = scene
    _, depth = render(client, FRONT_CAMERA, W, H, rgb=False, depth=True)
    only = np.zeros_like(depth)
    plane_pixels = [(H - 1, 0), (H - 1, W // 2), (H - 1, W - 1), (H - 10, 15), (H - 10, W - 15)]
    for v, u in plane_pixels:
        only[v, u] = depth[v, u]
    points, _ = depth_to_points(only, FRONT_CAMERA.fovy)
    world = transform_points(points, matrix=opencv_pose(FRONT_CAMERA))
    assert len(world) == len(plane_pixels)
    np.testing.assert_allclose(world[:, 2], 0.0, atol=3e-3)
    # The spread across the bottom row is set by fovy: a wrong one moves the corners off z = 0.
    assert np.ptp(world[:, 1]) > 0.1

    only[:] = 0
    only[H // 2, W // 2] = depth[H // 2, W // 2]
    (centre,) = transform_points(depth_to_points(only, 60.0)[0], matrix=opencv_pose(FRONT_CAMERA))
    assert centre[0] == pytest.approx(CUBE_CENTRE[0] + HALF, abs=3e-3)  # on the cube's +x face
    assert abs(centre[1]) < 3e-3 and 0 < centre[2] < 2 * HALF


def test_rgb_and_segmentation(scene) -> None:
    client, cube = scene
    images = render_images(client, FRONT_CAMERA, W, H, depth=True, segmentation=True)
    assert images.rgb.shape == (H, W, 3) and images.rgb.dtype == np.uint8
    assert images.rgb.flags.c_contiguous
    assert images.segmentation.dtype == np.int32 and images.segmentation[H // 2, W // 2] == cube
    red, green = images.rgb[H // 2, W // 2, :2].astype(int)
    assert red > green + 50  # the cube is red whatever the shading
    rgb, depth = render(client, FRONT_CAMERA, W, H)
    assert depth is None and rgb.shape == (H, W, 3)


def test_render_refuses_bad_requests(scene) -> None:
    client, _ = scene
    with pytest.raises(ValueError, match="at least one"):
        render(client, FRONT_CAMERA, W, H, rgb=False)
    with pytest.raises(ValueError, match="width"):
        render(client, FRONT_CAMERA, 0, H)


def test_rendering_a_closed_client_raises() -> None:
    client = connect(renderer="tiny")
    client.close()
    with pytest.raises(RuntimeError, match="closed"):
        render(client, FRONT_CAMERA, W, H)
