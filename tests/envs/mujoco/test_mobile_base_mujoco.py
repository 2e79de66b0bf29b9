"""The MuJoCo backend drives a robot's mobile base: velocity commands in the base's frame,
the measured velocity read back in that frame, arm poses relative to the moving base.

Shown on the HSR (the MuJoCo robot with a base); fixed robots are untouched by any of it.
"""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from rmb_lerobot.envs.mujoco.mobile_base import MobileBaseDrive, pose_in_body, yaw_rotation
from rmb_lerobot.envs.registry import entry_for
from rmb_lerobot.envs.robots import HSR, UR5E


@pytest.fixture(scope="module")
def env():
    env = entry_for("hsr_tidyup").make(cameras=(), render_mode=None)
    yield env
    env.close()


def drive(env, velocity, steps: int) -> None:
    action = env.command.astype(np.float32)
    action[-3:] = velocity
    for _ in range(steps):
        env.step(action)


def base_pose(env) -> tuple[np.ndarray, float]:
    pos, mat = env.sim.scene.body_pose(HSR.base.frame)
    return pos, float(np.arctan2(mat[1, 0], mat[0, 0]))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_velocity_is_commanded_and_measured_in_the_base_frame(env, seed):
    rng = np.random.default_rng(seed)
    env.reset(seed=seed, options={"world_idx": 0})
    turn = rng.uniform(0.3, 0.6) * rng.choice([-1, 1])
    drive(env, [0.0, 0.0, turn], 31)  # turn in place for a second
    _, yaw = base_pose(env)
    assert abs(yaw - turn) < 0.05  # the yaw rate is the command's
    velocity = np.append(rng.uniform(-0.2, 0.2, 2), 0.0)
    start, _ = base_pose(env)
    drive(env, velocity, 31)
    # Measured in the base frame: the command, whatever way the base faces.
    np.testing.assert_allclose(env.measured_base_velocity(), velocity, atol=0.01)
    moved, yaw_now = base_pose(env)
    expected = yaw_rotation(yaw) @ velocity[:2] * 31 * env.control_dt
    travel = (moved - start)[:2]
    # Along the commanded direction turned into the world; a little short (it accelerates).
    assert travel @ expected / (np.linalg.norm(travel) * np.linalg.norm(expected)) > 0.999
    assert 0.9 < np.linalg.norm(travel) / np.linalg.norm(expected) <= 1.0
    assert abs(yaw_now - yaw) < 0.01  # it stops turning (the rate decays in a few steps)
    np.testing.assert_allclose(env._agent_pos()[-3:], env.measured_base_velocity())


def test_arm_poses_are_in_the_moving_base_frame(env):
    env.reset(seed=0, options={"world_idx": 0})
    drive(env, [0.0, 0.0, 0.0], 10)
    before = env.eef_pose(env.measured_joint_pos())
    tcp_before, _ = env.sim.scene.site_pose(HSR.arms[0].tcp_frame)
    drive(env, [0.15, 0.1, 0.4], 40)
    drive(env, [0.0, 0.0, 0.0], 15)
    after = env.eef_pose(env.measured_joint_pos())
    tcp_after, _ = env.sim.scene.site_pose(HSR.arms[0].tcp_frame)
    assert np.linalg.norm(tcp_after - tcp_before) > 0.1  # the hand went along with the base
    np.testing.assert_allclose(after[:3], before[:3], atol=2e-3)  # same pose on the base
    # world_to_root uses the base's current pose: the world tcp maps to its root-frame pose.
    pos, rot = env.sim.scene.site_pose(HSR.arms[0].eef_frame)
    np.testing.assert_allclose(env.sim.world_to_root(0, pos, rot)[:3], after[:3], atol=1e-4)
    np.testing.assert_allclose(
        pose_in_body(env.sim.data, HSR.base.frame, pos, rot), env.sim.world_to_root(0, pos, rot)
    )


def test_the_base_velocity_is_bounded_by_the_record(env):
    low, high = env.action_space.low[-3:], env.action_space.high[-3:]
    np.testing.assert_allclose(high, [1.0, 1.0, 1.0])
    np.testing.assert_allclose(low, -high)
    env.reset(seed=0)
    action = env.command.astype(np.float32)
    action[-3:] = [5.0, -5.0, 5.0]
    assert np.allclose(env.command_from_action(action)[-3:], [1.0, -1.0, 1.0])


def test_a_fixed_robot_has_no_base_drive():
    env = entry_for("cable").make(cameras=(), render_mode=None)
    try:
        assert env.robot.base is None and env.measured_base_velocity() is None
        with pytest.raises(NotImplementedError, match="drives no mobile base"):
            env.sim.measured_base_velocity()
        with pytest.raises(ValueError, match="has no mobile base"):
            MobileBaseDrive(env.sim.model, UR5E)
    finally:
        env.close()


def test_a_model_without_the_base_joints_or_actuators_is_refused():
    spec = mujoco.MjSpec()
    body = spec.worldbody.add_body(name="base_link")
    body.add_geom(size=[0.1, 0, 0])
    with pytest.raises(ValueError, match="no base joint 'mobile_x_joint'"):
        MobileBaseDrive(spec.compile(), HSR)
    body.add_joint(name="mobile_x_joint", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[1, 0, 0])
    body.add_joint(name="mobile_y_joint", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 1, 0])
    body.add_joint(name="mobile_theta_joint", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 0, 1])
    with pytest.raises(ValueError, match="'mobile_x_joint' needs one actuator, has 0"):
        MobileBaseDrive(spec.compile(), HSR)
