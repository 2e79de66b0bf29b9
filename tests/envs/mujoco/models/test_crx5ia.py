"""RMB's FANUC CRX-5iA built from FANUC's dimensions: names, home, the datasheet's reach and
joint layout, the 2F-85 on the faceplate, collisions and a grasp."""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np
import pytest

from rmb_lerobot.envs.mujoco.kinematics import ArmKinematics
from rmb_lerobot.envs.mujoco.models.crx5ia import JOINTS, build_crx5ia
from rmb_lerobot.envs.mujoco.robots import MUJOCO_BUILDERS, check_model
from rmb_lerobot.envs.registry import ENVS
from rmb_lerobot.envs.robots import CRX5IA, UR5E, HandCamera, Pose
from rmb_lerobot.envs.workspace import RMB_TABLE

LINKS = [name for name, *_ in JOINTS]


def build():
    return build_crx5ia(CRX5IA)


def test_names_home_and_layout_are_rmbs(at_home):
    robot, model, _ = at_home(build)
    check_model(CRX5IA, robot, model)  # every name the record gives exists
    arm = robot.arms[0]
    assert arm.arm_joints == ("J1", "J2", "J3", "J4", "J5", "J6")
    assert arm.arm_actuators == tuple(f"act{i}" for i in range(1, 7))
    np.testing.assert_allclose(arm.home_arm_qpos, np.deg2rad([0, 0, 0, 0, -90, 0]))
    assert arm.gripper_joints == UR5E.arms[0].gripper.joints  # the UR5e's 2F-85
    assert arm.gripper_ctrl_range == (0.0, 255.0) and arm.home_gripper == 0.0
    assert (model.nu, model.nsensor, model.ncam) == (7, 2, 0)  # RMB's CRX has no hand camera
    assert robot.cameras == {} and CRX5IA.layout.num_joints == 7  # RMB's 7-D action
    np.testing.assert_allclose(robot.spec.body(arm.root_body).pos, (-0.5, 0.0, 0.8))
    # RMB's servos: kp 2000 (J1-J3), 500 (J4-J6).
    np.testing.assert_allclose(model.actuator_gainprm[:6, 0], [2000] * 3 + [500] * 3)
    assert MUJOCO_BUILDERS["crx5ia"](CRX5IA).name == "crx5ia"


def test_reach_and_joint_axes_are_the_datasheets(at_home):
    robot, model, data = at_home(build)
    arm = robot.arms[0]
    kin = ArmKinematics(model, arm)
    # Stretched (J3 at +90 deg: the forearm in line with the upper arm), the faceplate is the
    # datasheet's 994 mm reach from J2: 410 + 430 + 145 mm along the arm, 130 mm aside.
    q = np.zeros(6)
    q[2] = np.pi / 2
    data.qpos[kin.qpos_index] = q
    mujoco.mj_kinematics(model, data)
    reach = np.linalg.norm(data.site(arm.eef_site).xpos - data.body("J2_link").xpos)
    assert abs(reach - 0.994) < 1e-3
    # All joints at zero: J1 vertical, J2 / J3 / J5 about one horizontal axis, J4 / J6 about
    # the forearm's axis.
    data.qpos[kin.qpos_index] = 0.0
    mujoco.mj_kinematics(model, data)
    axes = data.xaxis[[model.joint(j).id for j in arm.arm_joints]]
    np.testing.assert_allclose(np.abs(axes[0]), [0, 0, 1], atol=1e-9)
    for i in (2, 4):
        np.testing.assert_allclose(abs(axes[i] @ axes[1]), 1.0, atol=1e-9)
    np.testing.assert_allclose(abs(axes[5] @ axes[3]), 1.0, atol=1e-9)
    np.testing.assert_allclose(axes[3] @ axes[1], 0.0, atol=1e-9)
    # The tool axis (faceplate z) is J6's axis.
    tool_z = data.site(arm.eef_site).xmat.reshape(3, 3)[:, 2]
    np.testing.assert_allclose(abs(tool_z @ axes[5]), 1.0, atol=1e-9)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_ik_reaches_random_poses_it_can_reach(seed):
    robot = build()
    kin = ArmKinematics(robot.spec.compile(), robot.arms[0])
    rng = np.random.default_rng(seed)
    home = np.asarray(robot.arms[0].home_arm_qpos)
    for _ in range(5):
        q = home + rng.uniform(-0.3, 0.3, 6)
        target = kin.fk(q)
        solution = kin.ik(target, home)
        assert solution.converged
        np.testing.assert_allclose(kin.fk(solution.qpos)[:3], target[:3], atol=1e-3)


def test_home_points_the_gripper_down_over_the_table(at_home):
    robot, _, data = at_home(build)
    arm = robot.arms[0]
    tcp = data.site(arm.tcp_site).xpos
    hx, hy = RMB_TABLE.table.half_size
    assert -hx < tcp[0] < hx and abs(tcp[1]) < hy
    assert 0.1 < tcp[2] - RMB_TABLE.table.top_z < 0.4
    tool_z = data.site(arm.eef_site).xmat.reshape(3, 3)[:, 2]
    np.testing.assert_allclose(tool_z, [0, 0, -1], atol=1e-6)


def test_arm_links_collide_with_the_world_but_not_with_each_other(at_home):
    robot, model, data = at_home(build)
    arm = robot.arms[0]
    qadr = [model.joint(name).qposadr[0] for name in arm.arm_joints]
    links = {model.body(name).id for name in [*LINKS, "base_link"]}
    lo, hi = model.jnt_range[[model.joint(n).id for n in arm.arm_joints]].T
    rng = np.random.default_rng(0)
    for _ in range(200):
        data.qpos[qadr] = rng.uniform(lo, hi)
        mujoco.mj_forward(model, data)
        for contact in data.contact[: data.ncon]:
            bodies = {model.geom_bodyid[contact.geom1], model.geom_bodyid[contact.geom2]}
            assert not bodies <= links, [model.body(b).name for b in bodies]
    robot = build()
    block = robot.spec.worldbody.add_body(name="block", mocap=True)
    block.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.03] * 3)  # default contact bits
    model = robot.spec.compile()
    data = mujoco.MjData(model)
    robot.arms[0].set_home(model, data)
    assert data.ncon == 0
    for body in ("J2_link", "J4_link", "J6_link"):
        data.mocap_pos[0] = data.body(body).xpos
        mujoco.mj_forward(model, data)
        assert data.ncon > 0, body


def test_gripper_command_closes_the_2f85_as_on_the_ur5e(sweep):
    values = sweep(build(), fractions=(0, 0.5, 1, 0))
    assert values[0] < 5 and values[3] < 5
    assert values[0] < values[1] < values[2]


@pytest.mark.parametrize(("offset_xy", "yaw"), [((0.0, 0.0), 0.0), ((-0.03, 0.02), -0.2)])
def test_holds_a_cube_lifted_10_cm(pick, offset_xy, yaw):
    # As on the UR5e: the pinch point 8 mm above the cube centre, the fingertips off the table.
    result = pick(build, 0, offset_xy, yaw, -0.008)
    assert result["finite"]
    assert result["rise"] > 0.05, result
    assert result["drift"] < 0.01, result


def test_builder_refuses_a_record_it_cannot_build():
    arm = CRX5IA.arms[0]
    camera = HandCamera("hand", Pose(), 60.0)
    with pytest.raises(ValueError, match="no hand camera"):
        build_crx5ia(
            dataclasses.replace(CRX5IA, arms=(dataclasses.replace(arm, hand_camera=camera),))
        )
    seven = dataclasses.replace(arm, joints=(*arm.joints, "J7"), home=(*arm.home, 0.0))
    with pytest.raises(ValueError, match="6 joints"):
        build_crx5ia(dataclasses.replace(CRX5IA, arms=(seven,)))


def test_env_names_are_rmbs_and_derive_from_the_record():
    entry = ENVS["crx5ia_cable"]
    assert entry.env_attr == "MujocoCrx5iaCableEnv"  # RMB's env class
    assert entry.gym_id == "rmb_lerobot/MujocoCrx5iaCable-v0"
    assert entry.lerobot_type == "rmb_crx5ia_cable" and entry.robot_type == "crx5ia"
    assert entry.cameras == ("front", "left", "right")
    assert entry.num_worlds == 6  # RMB's six pole positions
