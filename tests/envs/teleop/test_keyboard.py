"""The keyboard device: RMB's bindings as world-frame deltas, an arm switch, base keys."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from rmb_lerobot.envs.teleop.command import CommandTracker
from rmb_lerobot.envs.teleop.keyboard import KeyboardDevice, gripper_step_for
from rmb_lerobot.pose import quat_to_rotmat

# RMB's bindings: key -> (dpos (m), drpy (rad), dgripper) of one press.
RMB_BINDINGS = {
    "w": ((0.01, 0, 0), (0, 0, 0), 0),
    "s": ((-0.01, 0, 0), (0, 0, 0), 0),
    "a": ((0, 0.01, 0), (0, 0, 0), 0),
    "d": ((0, -0.01, 0), (0, 0, 0), 0),
    "q": ((0, 0, 0.01), (0, 0, 0), 0),
    "e": ((0, 0, -0.01), (0, 0, 0), 0),
    "j": ((0, 0, 0), (-0.05, 0, 0), 0),
    "l": ((0, 0, 0), (0.05, 0, 0), 0),
    "i": ((0, 0, 0), (0, 0.05, 0), 0),
    "k": ((0, 0, 0), (0, -0.05, 0), 0),
    "u": ((0, 0, 0), (0, 0, 0.1), 0),
    "o": ((0, 0, 0), (0, 0, -0.1), 0),
    "z": ((0, 0, 0), (0, 0, 0), 50),
    "x": ((0, 0, 0), (0, 0, 0), -50),
}


def press(device: KeyboardDevice, *keys: str):
    device.feed(list(keys))
    return device.read()


@pytest.mark.parametrize(("key", "expected"), RMB_BINDINGS.items())
def test_each_key_is_rmbs_delta(key, expected):
    reading = press(KeyboardDevice(), key)
    delta = reading.arms[0]
    np.testing.assert_allclose(delta.dpos, expected[0])
    np.testing.assert_allclose(delta.drpy, expected[1])
    assert delta.dgripper == expected[2]
    assert reading.base is None  # no base: no base command


def test_presses_add_up_and_are_consumed():
    device = KeyboardDevice()
    delta = press(device, "w", "w", "a", "unused", "n").arms[0]
    np.testing.assert_allclose(delta.dpos, [0.02, 0.01, 0])
    assert device.read().arms == {}  # nothing pressed since: the arm is not moved


def test_tab_and_digits_select_the_arm_of_a_bimanual_robot():
    device = KeyboardDevice(num_arms=2, gripper_step=(50, 0.2))
    assert set(press(device, "w").arms) == {0}
    reading = press(device, "tab", "z")
    assert set(reading.arms) == {1} and reading.arms[1].dgripper == 0.2
    reading = press(device, "q", "1", "e")  # a switch applies to the keys after it
    np.testing.assert_allclose(reading.arms[1].dpos, [0, 0, 0.01])
    np.testing.assert_allclose(reading.arms[0].dpos, [0, 0, -0.01])
    assert "3" not in device.keys and "tab" not in KeyboardDevice().keys


def test_base_keys_only_with_a_base():
    device = KeyboardDevice(has_base=True, base_speed=0.2, base_turn_speed=0.5)
    np.testing.assert_allclose(press(device, "up", "left", "[").base, [0.2, 0.2, 0.5])
    np.testing.assert_allclose(press(device).base, [0, 0, 0])
    assert press(KeyboardDevice(), "up").base is None


def test_gripper_step_scales_rmbs_50_to_the_range():
    assert gripper_step_for((0.0, 255.0)) == 50.0
    assert gripper_step_for((0.0, 1.0)) == pytest.approx(50 / 255)
    with pytest.raises(ValueError, match="one value per arm"):
        KeyboardDevice(num_arms=2, gripper_step=(1.0,))


def world_pose(env, arm, joints):
    """An arm's eef position and rotation in the world frame."""
    root = env.sim.world_to_root(arm, np.zeros(3), np.eye(3))
    root_from_world = quat_to_rotmat(root[3:])
    pose = env.sim.fk(arm, joints)
    pos = root_from_world.T @ (pose[:3] - root[:3])
    return pos, root_from_world.T @ quat_to_rotmat(pose[3:])


# Both poses of a step are IK solutions, each within the IK's tolerance (0.1 mm, 1 mrad).
POS_TOL, ROT_TOL = 2e-4, 2e-3


def test_key_presses_move_the_end_effector_in_the_world_frame(cable_env):
    """W, A, Q move the eef 1 cm along world x, y, z and U yaws it 0.1 rad about world z,
    whichever way the arm's base is turned (the UR5e's root frame is turned by pi)."""
    cable_env.reset(seed=0, options={"world_idx": 0})
    tracker, device = CommandTracker(cable_env), KeyboardDevice()
    arm = cable_env.robot.joint_slices()[0][0]
    for keys, dpos, drot in [
        (["w"], [0.01, 0, 0], np.eye(3)),
        (["a", "a"], [0, 0.02, 0], np.eye(3)),
        (["q", "e", "q"], [0, 0, 0.01], np.eye(3)),
        (["u"], [0, 0, 0], Rotation.from_euler("z", 0.1).as_matrix()),
    ]:
        pos0, rot0 = world_pose(cable_env, 0, tracker.command[arm])
        device.feed(keys)
        command = tracker.update(device.read())
        pos1, rot1 = world_pose(cable_env, 0, command[arm])
        np.testing.assert_allclose(pos1 - pos0, dpos, atol=POS_TOL)
        np.testing.assert_allclose(rot1 @ rot0.T, drot, atol=ROT_TOL)
    device.feed(["z", "z", "z", "z", "z", "z"])  # 6 x 50 closes the 0..255 gripper fully
    assert tracker.update(device.read())[6] == 255.0
    device.feed(["x"])
    assert tracker.update(device.read())[6] == 205.0


def test_arm_switch_moves_only_the_selected_arm_of_the_dual_ur5e(dual_env):
    dual_env.reset(seed=0, options={"world_idx": 0})
    tracker = CommandTracker(dual_env)
    device = KeyboardDevice(num_arms=2)
    (left, _), (right, _) = dual_env.robot.joint_slices()
    start = tracker.command.copy()
    device.feed(["tab", "q", "q"])  # the second arm up by 2 cm
    command = tracker.update(device.read())
    np.testing.assert_array_equal(command[left], start[left])
    pos0, _ = world_pose(dual_env, 1, start[right])
    pos1, _ = world_pose(dual_env, 1, command[right])
    np.testing.assert_allclose(pos1 - pos0, [0, 0, 0.02], atol=POS_TOL)
    device.feed(["1", "d"])  # back to the first arm: -y by 1 cm
    command2 = tracker.update(device.read())
    np.testing.assert_array_equal(command2[right], command[right])
    pos0, _ = world_pose(dual_env, 0, start[left])
    pos1, _ = world_pose(dual_env, 0, command2[left])
    np.testing.assert_allclose(pos1 - pos0, [0, -0.01, 0], atol=POS_TOL)
