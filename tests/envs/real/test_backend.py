"""The real backend under the env core, on the UR5e twin: no scene, 50 Hz in wall-clock time,
measured joints / velocities / wrench from the arm, cameras as RGB + depth + fovy, eef poses
from our kinematics, and the watchdog armed from the end of each reset."""

from __future__ import annotations

import time

import numpy as np
import pytest

from rmb_lerobot import keys as K
from rmb_lerobot.envs.real.config import make_real_env
from rmb_lerobot.envs.real.errors import WatchdogTripped
from rmb_lerobot.envs.real.limits import limits_for
from rmb_lerobot.envs.simulators import SIMULATORS
from rmb_lerobot.kinematics import UR5E as UR5E_DH

OPTIONS = {"image_size": (32, 24), "settle_s": 0.05, "reset_scale": 1.0, "watchdog_timeout": 0.5}


@pytest.fixture(scope="module")
def env():
    env = make_real_env("RealUR5eDemo", {"driver": "sim", **OPTIONS})
    yield env
    env.close()


def test_a_real_backend_has_no_scene_and_runs_at_50_hz(env):
    assert SIMULATORS["real"].fps == 50 and env.metadata["render_fps"] == 50
    assert env.sim.scene is None and env.sim.control_dt == 0.02
    _, info = env.reset(seed=0)
    _, reward, terminated, _, info = env.step(env.home_command)
    assert (reward, terminated, info["is_success"]) == (0.0, False, False)  # operator's call


def test_steps_are_paced_in_wall_clock_time(env):
    env.reset(seed=0)
    start = time.monotonic()
    for _ in range(20):
        env.step(env.home_command)
    elapsed = time.monotonic() - start
    assert elapsed >= 19 * 0.02  # never faster than the arm's period
    timing = env.sim.timing
    assert len(timing.ticks) == 21 and len(timing.latencies) == 20
    assert np.all(timing.periods() > 0)


def test_measurements_come_from_the_arm(env):
    env.reset(seed=0)
    obs, *_ = env.step(env.home_command)
    state = env.sim.state
    np.testing.assert_allclose(obs["agent_pos"], state.joints.astype(np.float32))
    twin = env.sim.device.twins[0].sim.read()
    np.testing.assert_allclose(state.joints[:6], twin.joint_pos, atol=0.05)
    limits = limits_for("ur5e")
    ((low, high),) = env.sim.joint_limits()
    np.testing.assert_array_equal(low, limits.low_array)
    np.testing.assert_array_equal(high, limits.high_array)


def test_step_data_holds_every_key_rmb_records(env):
    env.reset(seed=0)
    env.step(env.home_command)
    step = env.rmb_step_data(env.home_command)
    for key in (
        K.MEASURED_JOINT_POS,
        K.COMMAND_JOINT_POS,
        K.MEASURED_JOINT_VEL,
        K.MEASURED_GRIPPER_JOINT_POS,
        K.MEASURED_EEF_POSE,
        K.COMMAND_EEF_POSE,
        K.MEASURED_EEF_WRENCH,
    ):
        assert np.all(np.isfinite(step[key])), key
    assert step[K.MEASURED_EEF_WRENCH].shape == (6,)
    for camera in ("front", "hand"):
        assert step[K.rgb_image_key(camera)].shape == (24, 32, 3)
        depth = step[K.depth_image_key(camera)]
        assert depth.dtype == np.float32 and np.all(depth > 0)
    attrs = env.rmb_attrs()
    assert attrs[K.ATTR_ENV] == "RealUR5eDemoEnv"
    assert attrs[K.fovy_attr("hand")] == pytest.approx(62.0)
    # The eef pose is the MuJoCo model's flange in the arm's base frame: UR's DH table agrees.
    q = step[K.MEASURED_JOINT_POS][:6]
    dh = UR5E_DH.transform(q)[:3, 3]
    np.testing.assert_allclose(step[K.MEASURED_EEF_POSE][:3], dh, atol=2e-3)


def test_a_pause_in_the_command_stream_trips_the_watchdog_and_a_reset_recovers(env):
    env.reset(seed=0)
    env.step(env.home_command)
    time.sleep(0.02 + 0.5 + 0.3)  # the period, the timeout, a margin
    with pytest.raises(WatchdogTripped, match="no command"):
        env.step(env.home_command)
    env.reset(seed=0)  # the operator's restart
    env.step(env.home_command)


def test_the_end_of_an_episode_is_a_planned_pause(env):
    env.reset(seed=0)
    env.step(env.home_command)
    env.sim.end_episode()
    time.sleep(0.02 + 0.5 + 0.3)
    assert not any(layer.watchdog.tripped for layer in env.sim.device.layers)
