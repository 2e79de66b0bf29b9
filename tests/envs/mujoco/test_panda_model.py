"""RMB's Panda model: names, home pose over the table, gripper 0..1 = opening, a grasp."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from rmb_lerobot.envs.mujoco.models import panda
from rmb_lerobot.envs.robots import PANDA
from rmb_lerobot.envs.workspace import RMB_TABLE


def build_panda() -> panda.RobotModel:
    """RMB's Panda, from its record."""
    return panda.build_panda(PANDA)


def test_names_are_rmbs(at_home):
    robot, model, _ = at_home(build_panda)
    arm = robot.arms[0]
    assert arm.arm_joints == tuple(f"joint{i}" for i in range(1, 8))
    assert arm.arm_actuators == tuple(f"actuator{i}" for i in range(1, 8))
    assert arm.gripper_actuator == "actuator8"
    assert arm.gripper_joints == ("finger_joint1", "finger_joint2")
    assert (model.nq, model.nu, model.nsensor, model.ncam) == (9, 8, 2, 0)
    assert robot.cameras == {} and arm.hand_camera is None  # RMB's Panda has none
    np.testing.assert_allclose(arm.home_arm_qpos, np.deg2rad([0, 25, 0, -58, 0, 82, -40]))
    assert arm.home_gripper == 1.0 and arm.gripper_ctrl_range == (0.0, 1.0)
    np.testing.assert_allclose(robot.spec.body(arm.root_body).pos, PANDA.arms[0].mount.pos)
    # RMB's servos (panda_config.xml): kp 1000/1000/750/750/300/300/300.
    np.testing.assert_allclose(model.actuator_gainprm[:7, 0], [1000] * 2 + [750] * 2 + [300] * 3)


def test_home_tcp_is_over_the_table_in_front_of_the_arm(at_home):
    robot, _, data = at_home(build_panda)
    tcp = data.site(robot.arms[0].tcp_site).xpos
    hx, hy = RMB_TABLE.table.half_size
    assert PANDA.arms[0].mount.pos[0] < tcp[0] < hx and abs(tcp[1]) < hy
    assert tcp[2] > RMB_TABLE.table.top_z + 0.1


def test_gripper_command_is_the_finger_opening(sweep):
    values = sweep(build_panda())  # 0..1 = opening 0..0.04 m per finger, measured / 0.04
    np.testing.assert_allclose(values, [0, 0.25, 0.5, 0.75, 1, 0], atol=0.02)


def test_arm_links_never_touch_each_other(at_home):
    robot, model, data = at_home(build_panda)
    rng = np.random.default_rng(0)
    arm_q = [model.joint(name).qposadr[0] for name in robot.arms[0].arm_joints]
    lo, hi = model.jnt_range[[model.joint(n).id for n in robot.arms[0].arm_joints]].T
    for _ in range(300):
        data.qpos[arm_q] = rng.uniform(lo, hi)
        mujoco.mj_forward(model, data)
        assert data.ncon == 0


def test_arm_links_collide_with_the_world():
    robot = build_panda()
    block = robot.spec.worldbody.add_body(name="block", mocap=True)
    block.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.03] * 3)  # default contact bits
    model = robot.spec.compile()
    data = mujoco.MjData(model)
    robot.arms[0].set_home(model, data)
    assert data.ncon == 0
    for body in ("panda_link4", "panda_hand", "panda_leftfinger"):
        data.mocap_pos[0] = data.body(body).xpos  # the block inside the link
        mujoco.mj_forward(model, data)
        assert data.ncon > 0, body


@pytest.mark.parametrize(
    ("offset_xy", "yaw"), [((0.0, 0.0), 0.0), ((0.03, -0.025), 0.25), ((-0.035, 0.03), -0.3)]
)
def test_holds_a_cube_lifted_10_cm_after_a_step_close(pick, offset_xy, yaw):
    # The TCP is between the fingertip pads; grasp 8 mm above the cube centre so the tips
    # clear the table.
    result = pick(build_panda, 0, offset_xy, yaw, -0.008)
    assert result["finite"]
    assert result["rise"] > 0.05, result  # RMB's servos sag: the TCP rises ~6 cm of 10
    assert result["drift"] < 0.01, result
    assert abs(result["gripper"] - 0.375) < 0.05, result  # 3 cm between the fingers


@pytest.mark.parametrize(
    ("shape", "size", "width"),
    [
        ("box", (0.015, 0.015, 0.015), 0.03),  # a 3 cm cube
        ("box", (0.015, 0.005, 0.015), 0.01),  # a 1 cm plate
        ("capsule", (0.01, 0.02, 0.0), 0.02),  # a link of RMB's cable (radius 1 cm)
    ],
)
def test_a_step_close_holds_what_is_between_the_fingers(settle, shape, size, width):
    # RMB's finger actuator is stiff (gear 25): the fingers must stop at the object, not pass
    # through it, and hold it against gravity.
    robot = build_panda()
    arm = robot.arms[0]
    body = robot.spec.worldbody.add_body(name="object")
    body.add_freejoint()
    geom_type = {"box": mujoco.mjtGeom.mjGEOM_BOX, "capsule": mujoco.mjtGeom.mjGEOM_CAPSULE}
    # In the hand's frame (fingers close along y); the capsule's axis along x.
    quat = [1, 0, 1, 0] if shape == "capsule" else [1, 0, 0, 0]
    body.add_geom(type=geom_type[shape], size=list(size), quat=quat, mass=0.05)
    model = robot.spec.compile()
    data = mujoco.MjData(model)
    arm.set_home(model, data)
    tcp = data.site(arm.tcp_site)
    qpos = model.body("object").jntadr[0]
    data.qpos[qpos : qpos + 3] = tcp.xpos
    mujoco.mju_mat2Quat(data.qpos[qpos + 3 : qpos + 7], tcp.xmat)
    mujoco.mj_forward(model, data)
    data.actuator(arm.gripper_actuator).ctrl[0] = 0.0  # step from open to closed
    settle(model, data, 2.0)
    assert np.linalg.norm(data.body("object").xpos - tcp.xpos) < 0.01
    assert abs(arm.gripper_value(data) - width / 0.08) < 0.03  # opening = the object's width
