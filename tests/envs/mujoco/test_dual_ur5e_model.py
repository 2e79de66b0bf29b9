"""RMB's dual UR5e: two of the repo's UR5e + 2F-85 under left/ and right/ at RMB's mounts."""

from __future__ import annotations

import numpy as np
import pytest

from rmb_lerobot.envs.mujoco.models import dual_ur5e
from rmb_lerobot.envs.mujoco.robot import UR5E_2F85, build_robot_spec
from rmb_lerobot.envs.robots import UR5E, UR5E_DUAL
from rmb_lerobot.envs.workspace import RMB_TABLE

# RMB's mounts (env_ur5e_dual_cable.xml lines 39-44), as the record gives them.
RMB_MOUNT_POS = {"left/": (-0.605, 0.4, 0.8), "right/": (-0.605, -0.4, 0.8)}


def build_dual_ur5e() -> dual_ur5e.RobotModel:
    """RMB's dual UR5e, from its record."""
    return dual_ur5e.build_dual_ur5e(UR5E_DUAL)


def test_names_are_rmbs_with_prefixes(at_home):
    robot, model, _ = at_home(build_dual_ur5e)
    left, right = robot.arms
    assert left.arm_joints[0] == "left/shoulder_pan_joint"
    assert right.gripper_actuator == "right/gripper/fingers_actuator"
    actuators = [model.actuator(i).name for i in range(model.nu)]
    assert actuators == [
        *left.arm_actuators,
        left.gripper_actuator,
        *right.arm_actuators,
        right.gripper_actuator,
    ]
    assert (model.nq, model.nu) == (2 * 14, 14)
    sensors = {model.sensor(i).name for i in range(model.nsensor)}
    assert sensors == {"left/force", "left/torque", "right/force", "right/torque"}
    for arm in robot.arms:
        assert model.sensor(arm.force_sensor).objid[0] == model.site(arm.ft_site).id
    assert robot.cameras == {"left_hand": "left/hand", "right_hand": "right/hand"}
    assert all(model.camera(name).id >= 0 for name in robot.cameras.values())
    np.testing.assert_allclose(
        left.home_arm_qpos, np.pi * np.array([0.9, -0.4, -0.65, -0.2, 0.5, 0.5])
    )
    np.testing.assert_allclose(
        right.home_arm_qpos, np.pi * np.array([0.1, -0.6, 0.65, -0.8, -0.5, -0.5])
    )


def test_arms_stand_where_rmbs_do_and_are_the_single_ur5e(at_home):
    robot, model, data = at_home(build_dual_ur5e)
    single = build_robot_spec(UR5E_2F85, UR5E.arms[0]).compile()
    for arm, prefix in zip(robot.arms, ("left/", "right/"), strict=True):
        np.testing.assert_allclose(data.body(arm.root_body).xpos, RMB_MOUNT_POS[prefix])
        np.testing.assert_allclose(data.body(arm.base_body).xquat, [1, 0, 0, 0], atol=1e-12)
        for i in range(1, single.nbody):  # same bodies, masses and joints as the single arm
            name = single.body(i).name
            assert model.body(prefix + name).mass[0] == pytest.approx(single.body(i).mass[0])
        for joint in UR5E.arms[0].joints:
            np.testing.assert_array_equal(
                model.joint(prefix + joint).range, single.joint(joint).range
            )
    assert model.opt.cone == single.opt.cone and model.opt.impratio == single.opt.impratio
    assert model.opt.timestep == 0.004


def test_home_tcps_are_over_the_table_each_on_its_side(at_home):
    robot, _, data = at_home(build_dual_ur5e)
    hx, hy = RMB_TABLE.table.half_size
    left, right = (data.site(arm.tcp_site).xpos for arm in robot.arms)
    for tcp in (left, right):
        assert -hx < tcp[0] < hx and abs(tcp[1]) < hy and tcp[2] > RMB_TABLE.table.top_z + 0.1
    assert left[1] > 0.05 and right[1] < -0.05


@pytest.mark.parametrize("arm_index", [0, 1])
def test_each_gripper_maps_commands_like_the_single_ur5e(sweep, arm_index):
    values = sweep(build_dual_ur5e(), arm_index)
    np.testing.assert_allclose(values, [0, 63.75, 127.5, 191.25, 255, 0], atol=6)


def test_one_gripper_closing_leaves_the_other_open(at_home, settle):
    robot, model, data = at_home(build_dual_ur5e)
    left, right = robot.arms
    data.actuator(left.gripper_actuator).ctrl[0] = 255
    settle(model, data, 1.0)
    assert left.gripper_value(data) > 240 and right.gripper_value(data) < 5


@pytest.mark.parametrize(
    ("arm_index", "offset_xy", "yaw"), [(0, (0.0, 0.0), 0.0), (1, (0.03, -0.02), 0.2)]
)
def test_holds_a_cube_lifted_10_cm(pick, arm_index, offset_xy, yaw):
    result = pick(build_dual_ur5e, arm_index, offset_xy, yaw, -0.008)
    assert result["finite"]
    assert result["rise"] > 0.08, result
    assert result["drift"] < 0.01, result
    assert 120 < result["gripper"] < 230, result  # closed on the cube, not empty (~255)
