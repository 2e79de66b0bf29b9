"""Offscreen rendering: shapes, dtypes, and depth in metres."""

import numpy as np
import pytest

from rmb_lerobot.envs.mujoco.render import MultiCameraRenderer
from rmb_lerobot.envs.workspace import RMB_TABLE


def test_observation_images_have_the_requested_size(camera_env):
    obs, _ = camera_env.reset(seed=0)
    assert set(obs["pixels"]) == {"front", "hand"} == set(obs["depth"])
    for cam in ("front", "hand"):
        assert obs["pixels"][cam].shape == (48, 64, 3) and obs["pixels"][cam].dtype == np.uint8
        assert obs["depth"][cam].shape == (48, 64) and obs["depth"][cam].dtype == np.uint16
        assert obs["pixels"][cam].std() > 5  # not a blank image
    assert camera_env.render().shape == (48, 64, 3)


def test_front_depth_at_the_image_centre_is_the_distance_to_the_table(camera_env):
    camera_env.reset(seed=0, options={"world_idx": 0})
    renderer = camera_env.sim._get_renderer()
    _, depth = renderer.render(camera_env.sim.data, ["front"], rgb=False, depth=True)
    front = next(c for c in RMB_TABLE.cameras if c.name == "front")
    expected = np.linalg.norm(np.subtract(front.lookat, front.pos))  # optical axis hits lookat
    h, w = depth["front"].shape
    centre = depth["front"][h // 2 - 1 : h // 2 + 1, w // 2 - 1 : w // 2 + 1].mean()
    assert centre == pytest.approx(expected, abs=0.02)
    mm = camera_env.rmb_step_data()
    assert mm["front_depth_image"].dtype == np.float32


def test_hand_camera_sees_the_peg_close_and_the_table_further(camera_env):
    obs, _ = camera_env.reset(seed=0)
    depth_m = camera_env.rmb_step_data()["hand_depth_image"]
    assert 0.01 < depth_m.min() < 0.3  # gripper / peg right in front of the lens
    assert 0.15 < np.median(depth_m) < 1.0  # the table about 0.3 m below the camera
    assert np.abs(obs["depth"]["hand"].astype(np.float64) / 1000 - depth_m).max() <= 5e-4 + 1e-6


def test_renderer_rejects_bad_cameras_and_sizes(camera_env):
    renderer = camera_env.sim._get_renderer()
    with pytest.raises(ValueError, match="unknown camera 'nope'"):
        renderer.render(camera_env.sim.data, ["nope"])
    with pytest.raises(ValueError, match="exceeds the model's offscreen buffer"):
        MultiCameraRenderer(camera_env.sim.model, 4000, 3000)
    assert renderer.render(camera_env.sim.data, []) == ({}, {})


def test_fovy_per_camera(camera_env):
    assert camera_env.fovy("hand") == pytest.approx(62.0)
    assert camera_env.fovy("front") == pytest.approx(45.0)
    with pytest.raises(ValueError, match="unknown camera"):
        camera_env.fovy("top")
