"""RealRobot: a robot record's arms behind their safety layers, with LeRobot cameras.

Against the MuJoCo twins on loopback (``driver="sim"``): the joint vector is RMB's layout,
every command goes through the layers (a far target is clamped, not sent), reset moves take
RMB's per-robot scale, cameras come through LeRobot's own factory and give RGB + depth + fovy.
Waits poll with generous bounds; nothing asserts exact timing (the machine is shared).
"""

from __future__ import annotations

import inspect
import time

import numpy as np
import pytest
from lerobot.cameras import make_cameras_from_configs

from rmb_lerobot.envs.real.cameras import TwinCamera, TwinCameraConfig, fovy_from_intrinsics
from rmb_lerobot.envs.real.device import RealRobot, make_real_robot
from rmb_lerobot.envs.real.limits import limits_for
from rmb_lerobot.envs.real.testing import wait_for
from rmb_lerobot.envs.robots import UR5E, UR5E_DUAL

SMALL = {"width": 32, "height": 24}


@pytest.fixture(scope="module")
def ur5e():
    cameras = {
        "front": TwinCameraConfig(**SMALL),
        "hand": TwinCameraConfig(view="hand", **SMALL),
    }
    with make_real_robot("ur5e", cameras=cameras) as robot:
        yield robot


def test_readings_are_rmb_vectors(ur5e):
    state = ur5e.read()
    assert ur5e.read_joints().shape == (UR5E.layout.num_joints,)  # 6 joints + gripper
    assert ur5e.read_velocities().shape == (7,) and ur5e.read_velocities()[6] == 0.0
    assert ur5e.read_wrench().shape == (6,)
    sim = ur5e.twins[0].sim.read()
    np.testing.assert_allclose(state.joints[:6], sim.joint_pos, atol=0.05)


def test_a_far_command_is_clamped_by_the_layer_not_sent():
    """send() returns what was sent: a target 1 rad away moves at most 2 v_lim dt."""
    with make_real_robot("ur5e") as robot:
        measured = robot.read_joints()
        target = measured + np.r_[np.full(6, 0.5), 0.0]  # < 90 deg: clamped, not refused
        sent = robot.send(target, 0.02)
        reach = 2.0 * limits_for("ur5e").v_lim * 0.02
        assert np.all(np.abs(sent[:6] - measured[:6]) <= reach + 1e-9)
        assert not np.allclose(sent, target)


def test_reset_moves_take_each_robots_rmb_scale():
    for name, scale in (("ur5e", 0.3), ("xarm7", 0.1)):
        with make_real_robot(name) as robot:
            home = robot.read_joints()
            goal = home.copy()
            goal[0] += 0.2
            sent = robot.move_to(goal)
            v_lim = robot.layers[0].limits.v_lim
            assert robot.last_move_duration == pytest.approx(
                max(0.1, 0.2 / (scale * v_lim)), rel=0.05
            )
            np.testing.assert_allclose(sent[:-1], goal[:-1])
            assert wait_for(lambda r=robot, g=goal: abs(r.read_joints()[0] - g[0]) < 0.02)


def test_cameras_give_rgb_depth_and_fovy(ur5e):
    frames = ur5e.read_cameras()
    assert set(frames) == {"front", "hand"}
    for frame in frames.values():
        assert frame.rgb.shape == (24, 32, 3) and frame.rgb.dtype == np.uint8
        assert frame.depth is not None and frame.depth.shape == (24, 32)
        assert frame.depth.dtype == np.float32 and np.all(frame.depth > 0)
        assert frame.rgb.std() > 0  # something was rendered
    assert frames["hand"].fovy == UR5E.arms[0].hand_camera.fovy  # the record's wrist camera


def test_lerobot_makes_the_twin_camera_from_its_config_type():
    cameras = make_cameras_from_configs({"front": TwinCameraConfig(**SMALL)})
    assert isinstance(cameras["front"], TwinCamera)
    assert TwinCameraConfig(**SMALL).type == "rmb_twin"


def test_fovy_from_intrinsics_is_rmbs_formula():
    assert fovy_from_intrinsics(480, 240.0) == pytest.approx(90.0)
    assert fovy_from_intrinsics(480, 385.0) == pytest.approx(np.degrees(2 * np.arctan(240 / 385)))


def test_dual_robot_drives_both_arms_from_one_vector():
    with make_real_robot("ur5e_dual") as robot:
        assert len(robot.layers) == 2 and robot.twins[0] is not robot.twins[1]
        q = robot.read_joints()
        assert q.shape == (UR5E_DUAL.layout.num_joints,) and robot.read_wrench().shape == (12,)
        goal = q.copy()
        goal[[0, 7]] += (0.1, -0.1)  # the first joint of each arm
        robot.move_to(goal, scale=1.0)
        assert wait_for(lambda: np.allclose(robot.read_joints()[[0, 7]], goal[[0, 7]], atol=0.02))


def test_disconnect_is_idempotent_and_stops_the_arm():
    robot = make_real_robot("ur5e")
    robot.connect()
    sim = robot.twins[0].sim
    goal = robot.read_joints()
    goal[0] += 1.5
    robot.move_to(goal, scale=0.1, wait=False)  # a 4.5 s move under way ...
    time.sleep(0.1)
    robot.disconnect()  # ... is stopped long before it ends
    robot.disconnect()
    assert not robot.is_connected
    assert abs(sim.read().joint_pos[0] - goal[0]) > 0.5


def test_no_default_address_but_loopback_and_bad_input_named():
    defaults = inspect.signature(make_real_robot).parameters
    assert defaults["hosts"].default == ("127.0.0.1",) and defaults["driver"].default == "sim"
    with pytest.raises(ValueError, match="no real robot 'panda'"):
        make_real_robot("panda")
    with pytest.raises(ValueError, match="2 address"):
        make_real_robot("ur5e_dual", driver="sdk", hosts=("127.0.0.1",))
    with pytest.raises(ValueError, match="loopback"):
        make_real_robot("ur5e", hosts=("192.0.2.1",))  # sim needs loopback; nothing connects
    with pytest.raises(ValueError, match="1 arm"):
        RealRobot(UR5E, [])
