"""The robot record types: mobile bases, body cameras, gripper kinds, one module per robot."""

from __future__ import annotations

import dataclasses
import importlib
import pkgutil

import numpy as np
import pytest

import rmb_lerobot.envs.robots as robots_package
from rmb_lerobot import keys as K
from rmb_lerobot.envs.robots import (
    PANDA,
    ROBOTS,
    SAWYER,
    UR5E,
    UR5E_DUAL,
    XARM7,
    BodyCamera,
    GripperKind,
    MobileBase,
    Pose,
    Robot,
)

HEAD = BodyCamera("head", parent="head_tilt_link", pose=Pose(pos=(0.02, 0.0, 0.1)), fovy=58.0)
BASE = MobileBase(
    joints=("mobile_x_joint", "mobile_y_joint", "mobile_theta_joint"),
    frame="base_link",
    max_linear_vel=0.3,
    max_angular_vel=1.0,
)


def test_each_robot_module_holds_one_record_and_the_package_registers_it():
    modules = [
        info.name for info in pkgutil.iter_modules(robots_package.__path__) if info.name != "common"
    ]
    assert {"ur5e", "dual_ur5e", "xarm7", "panda", "sawyer"} <= set(modules)
    for name in modules:
        module = importlib.import_module(f"rmb_lerobot.envs.robots.{name}")
        records = [v for v in vars(module).values() if isinstance(v, Robot)]
        # dual_ur5e imports UR5E to derive its arms; count only the records defined there.
        own = [r for r in records if r is not UR5E or name == "ur5e"]
        assert len(own) == 1, (name, [r.name for r in own])
        assert ROBOTS[own[0].name] is own[0], f"{name}.py's record is not in ROBOTS"


def test_fixed_robots_have_no_base_and_their_commands_are_their_joint_vectors():
    for robot in (UR5E, UR5E_DUAL, XARM7, PANDA, SAWYER):
        assert robot.base is None and robot.base_slice is None
        assert robot.layout.mobile_dim == 0
        assert robot.command_size == robot.layout.num_joints == len(robot.home_command())


def test_gripper_kinds_of_rmbs_robots():
    assert UR5E.arms[0].gripper.kind is GripperKind.PARALLEL  # 2F-85, 0..255
    assert XARM7.arms[0].gripper.kind is GripperKind.PARALLEL  # 0..255 from six finger joints
    assert PANDA.arms[0].gripper.kind is GripperKind.SLIDE  # opening 0..1
    assert SAWYER.arms[0].gripper.kind is GripperKind.SLIDE  # WSG50, metres
    single = UR5E.arms[0].gripper
    for arm in UR5E_DUAL.arms:  # each dual arm keeps the UR5e's gripper under its prefix
        prefixed = tuple(f"{arm.name}/{joint}" for joint in single.joints)
        assert arm.gripper == dataclasses.replace(single, joints=prefixed)


def test_closed_fraction_reads_every_gripper_the_same_way():
    panda, ur5e, sawyer = (r.arms[0].gripper for r in (PANDA, UR5E, SAWYER))
    assert panda.closed_fraction(1.0) == 0.0 and panda.closed_fraction(0.0) == 1.0
    assert panda.closed_fraction(0.25) == pytest.approx(0.75)  # 0..1 runs open -> closed down
    assert ur5e.closed_fraction(127.5) == pytest.approx(0.5)
    assert ur5e.closed_fraction(300.0) == 1.0  # clipped
    assert sawyer.closed_fraction(sawyer.open) == 0.0
    assert sawyer.closed_fraction(sawyer.closed) == 1.0


def test_an_unknown_gripper_kind_is_refused():
    with pytest.raises(ValueError, match="gripper kind must be one of"):
        dataclasses.replace(UR5E.arms[0].gripper, kind="suction")


def test_a_robot_on_a_mobile_base_with_a_head_camera():
    robot = dataclasses.replace(UR5E, name="mobile_ur5e", base=BASE, body_cameras=(HEAD,))
    assert robot.layout == K.RobotLayout(num_joints=7, mobile_dim=3)
    assert robot.command_size == 10
    assert robot.base_slice == slice(7, 10)
    home = robot.home_command()
    np.testing.assert_array_equal(home[:7], UR5E.home_command())
    np.testing.assert_array_equal(home[7:], np.zeros(3))  # the base starts at rest
    assert robot.cameras == ("hand", "head")  # hand cameras first, then the body's
    low, high = BASE.velocity_bounds
    np.testing.assert_array_equal(high, [0.3, 0.3, 1.0])
    np.testing.assert_array_equal(low, -high)


def test_camera_names_may_not_repeat_across_hands_and_body():
    with pytest.raises(ValueError, match="camera names repeat"):
        dataclasses.replace(UR5E, body_cameras=(dataclasses.replace(HEAD, name="hand"),))


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"joints": ("x", "y")}, "needs 3 distinct joints"),
        ({"joints": ("x", "x", "yaw")}, "needs 3 distinct joints"),
        ({"max_linear_vel": 0.0}, "bounds must be > 0"),
        ({"max_angular_vel": -1.0}, "bounds must be > 0"),
    ],
)
def test_a_bad_mobile_base_is_refused(change, message):
    with pytest.raises(ValueError, match=message):
        dataclasses.replace(BASE, **change)


def test_a_layout_base_velocity_has_three_numbers_or_none():
    with pytest.raises(ValueError, match="mobile_dim must be 0"):
        K.RobotLayout(num_joints=7, mobile_dim=2)
    layout = K.RobotLayout(num_joints=7, mobile_dim=3)
    assert K.spec(K.COMMAND_MOBILE_OMNI_VEL).dim(layout) == 3
