"""A rendered step's depth and RGB are what the float64 path before issue 27 gave, exactly."""

from __future__ import annotations

import numpy as np
import pytest

from rmb_lerobot.envs.registry import compose
from rmb_lerobot.envs.tasks.insert import InsertTask

CAMERAS = ("front", "left", "right", "hand")


def reference_metres_to_mm(depth_m: np.ndarray) -> np.ndarray:
    """The millimetre conversion of every step before issue 27: float64 image arithmetic."""
    mm = np.rint(np.asarray(depth_m, dtype=np.float64) * 1000.0)
    valid = np.isfinite(mm) & (mm >= 0) & (mm <= 65535)
    return np.where(valid, mm, 0).astype(np.uint16)


def reference_linearize(buffer: np.ndarray, near: float, far: float) -> np.ndarray:
    """OpenGL depth buffer -> metres as the renderer computed it before issue 27."""
    out = np.multiply(buffer, -np.float32(1.0 - near / far), dtype=np.float32)
    out += np.float32(1.0)
    return np.divide(np.float32(near), out, out=out)


@pytest.fixture(scope="module")
def four_camera_env():
    """Insert with RMB's four cameras, RGB + depth, small enough for a unit test."""
    env = compose(InsertTask(), cameras=CAMERAS, image_size=(160, 120), depth=True)
    yield env
    env.close()


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_step_depth_mm_and_rgb_equal_the_float64_path(four_camera_env, seed):
    env = four_camera_env
    env.reset(seed=seed)
    for _ in range(3):
        obs, *_ = env.step(env.home_command)
    renderer = env.sim._get_renderer()
    rgb, depth_m = renderer.render(env.sim.data, list(CAMERAS), rgb=True, depth=True)
    for camera in CAMERAS:
        assert obs["depth"][camera].dtype == np.uint16
        np.testing.assert_array_equal(obs["depth"][camera], reference_metres_to_mm(depth_m[camera]))
        np.testing.assert_array_equal(obs["pixels"][camera], rgb[camera])
        assert np.count_nonzero(obs["depth"][camera]) > 0  # the scene is in view


def test_linearised_depth_equals_the_reference_formula(four_camera_env):
    renderer = four_camera_env.sim._get_renderer()
    buffer = np.random.default_rng(0).uniform(0.0, 1.0, (120, 160)).astype(np.float32)
    buffer[0, :3] = [0.0, 1.0, 0.5]
    expected = reference_linearize(buffer, renderer._near, renderer._far)
    np.testing.assert_array_equal(renderer.linearize_depth(buffer), expected)
    np.testing.assert_array_equal(renderer.linearize_depth(np.flipud(buffer)), expected[::-1])
