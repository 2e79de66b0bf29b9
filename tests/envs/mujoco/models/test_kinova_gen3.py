"""RMB's Kinova Gen3 built from Kinova's kinematics: names, home, FK against the published DH
table, the 2F-85 on the flange, the wrist camera, collisions and a grasp."""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np
import pytest

from rmb_lerobot.envs.mujoco.kinematics import ArmKinematics
from rmb_lerobot.envs.mujoco.models.kinova_gen3 import LINKS, build_kinova_gen3
from rmb_lerobot.envs.mujoco.robots import MUJOCO_BUILDERS, check_model
from rmb_lerobot.envs.registry import ENVS
from rmb_lerobot.envs.robots import KINOVA_GEN3, UR5E
from rmb_lerobot.envs.workspace import RMB_TABLE


def build():
    return build_kinova_gen3(KINOVA_GEN3)


def kinova_dh_tool_pose(q: np.ndarray) -> np.ndarray:
    """The tool frame from the Gen3 user guide's classic DH table (base frame turned by pi
    about x, then per joint alpha, d, theta offset), as a 4x4 matrix in the base frame."""
    d = [-(0.1564 + 0.1284), -(0.0054 + 0.0064), -(0.2104 + 0.2104), -(0.0064 + 0.0064)]
    d += [-(0.2084 + 0.1059), 0.0, -(0.1059 + 0.0615)]
    alpha = [np.pi / 2] * 6 + [np.pi]
    offset = [0.0] + [np.pi] * 6
    pose = np.diag([1.0, -1.0, -1.0, 1.0])
    for i in range(7):
        ca, sa = np.cos(alpha[i]), np.sin(alpha[i])
        ct, st = np.cos(q[i] + offset[i]), np.sin(q[i] + offset[i])
        pose = pose @ np.array(
            [
                [ct, -st * ca, st * sa, 0.0],
                [st, ct * ca, -ct * sa, 0.0],
                [0, sa, ca, d[i]],
                [0, 0, 0, 1],
            ]
        )
    return pose


def test_names_home_and_layout_are_rmbs(at_home):
    robot, model, _ = at_home(build)
    check_model(KINOVA_GEN3, robot, model)  # every name the record gives exists
    arm = robot.arms[0]
    assert arm.arm_joints == tuple(f"joint_{i}" for i in range(1, 8))
    np.testing.assert_allclose(arm.home_arm_qpos, np.deg2rad([0, 20, 0, 100, 0, 60, 0]))
    assert arm.gripper_joints == UR5E.arms[0].gripper.joints  # the UR5e's 2F-85
    assert arm.gripper_ctrl_range == (0.0, 255.0) and arm.home_gripper == 0.0
    assert (model.nu, model.nsensor, model.ncam) == (8, 2, 1)  # 7 servos + fingers; F/T; hand
    assert KINOVA_GEN3.layout.num_joints == 8  # RMB's 8-D action and joint vector
    np.testing.assert_allclose(robot.spec.body(arm.root_body).pos, (-0.5, 0.0, 0.8))
    assert robot.stand is not None and robot.stand.half_size == (0.22, 0.22, 0.4)
    assert MUJOCO_BUILDERS["kinova_gen3"](KINOVA_GEN3).name == "kinova_gen3"


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_tool_frame_follows_kinovas_published_dh_table(seed):
    """Independent check of the joint origins: the user guide's DH table (mm-rounded offsets)
    gives the same tool pose within a millimetre at random joint angles."""
    robot = build()
    kin = ArmKinematics(robot.spec.compile(), robot.arms[0])
    rng = np.random.default_rng(seed)
    for _ in range(10):
        q = rng.uniform(kin.lower, kin.upper)
        pose = kin.fk(q)
        rot = np.empty(9)
        mujoco.mju_quat2Mat(rot, pose[3:])
        expected = kinova_dh_tool_pose(q)
        assert np.linalg.norm(pose[:3] - expected[:3, 3]) < 1e-3
        np.testing.assert_allclose(rot.reshape(3, 3), expected[:3, :3], atol=1e-6)


def test_stretched_upwards_the_arm_is_as_tall_as_the_datasheet_says(at_home):
    robot, model, data = at_home(build)
    arm = robot.arms[0]
    data.qpos[: len(LINKS)] = 0.0
    mujoco.mj_kinematics(model, data)
    base = data.body(arm.root_body).xpos
    tool = data.site(arm.eef_site).xpos
    assert abs(tool[2] - base[2] - 1.1874) < 1e-3  # 156.4 + 128.4 + 2 x 210.4 + 208.4 + ...
    # Joints 1, 3, 5, 7 turn about the vertical, 2, 4, 6 about one horizontal axis.
    axes = data.xaxis[[model.joint(j).id for j in arm.arm_joints]]
    np.testing.assert_allclose(np.abs(axes[::2, 2]), 1.0, atol=1e-9)
    np.testing.assert_allclose(np.abs(axes[1::2] @ axes[1]), 1.0, atol=1e-9)
    np.testing.assert_allclose(axes[1::2, 2], 0.0, atol=1e-9)


def test_home_points_the_gripper_down_over_the_table_and_the_camera_with_it(at_home):
    robot, _, data = at_home(build)
    arm = robot.arms[0]
    tcp = data.site(arm.tcp_site).xpos
    hx, hy = RMB_TABLE.table.half_size
    assert -hx < tcp[0] < hx and abs(tcp[1]) < hy
    assert 0.1 < tcp[2] - RMB_TABLE.table.top_z < 0.3
    tool_z = data.site(arm.eef_site).xmat.reshape(3, 3)[:, 2]
    np.testing.assert_allclose(tool_z, [0, 0, -1], atol=1e-6)
    camera = data.cam("hand")
    forward = -camera.xmat.reshape(3, 3)[:, 2]  # MuJoCo cameras look along -z
    assert forward @ tool_z > 0.99
    # 4 cm beside the tool axis, the fingertips ahead of the lens.
    offset = camera.xpos - data.site(arm.eef_site).xpos
    assert 0.04 < np.linalg.norm(offset - (offset @ tool_z) * tool_z) < 0.07
    assert (tcp - camera.xpos) @ tool_z > 0.1


def test_arm_links_collide_with_the_world_but_not_with_each_other(at_home):
    robot, model, data = at_home(build)
    arm = robot.arms[0]
    qadr = [model.joint(name).qposadr[0] for name in arm.arm_joints]
    links = {model.body(name).id for name in LINKS}
    rng = np.random.default_rng(0)
    for _ in range(200):
        data.qpos[qadr] = rng.uniform(-np.pi, np.pi, len(qadr))
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
    for body in ("half_arm_2_link", "forearm_link", "bracelet_link"):
        data.mocap_pos[0] = data.body(body).xpos
        mujoco.mj_forward(model, data)
        assert data.ncon > 0, body


def test_gripper_command_closes_the_2f85_as_on_the_ur5e(sweep):
    values = sweep(build(), fractions=(0, 0.5, 1, 0))
    assert values[0] < 5 and values[3] < 5  # open, and open again
    assert values[0] < values[1] < values[2]  # the measured value follows the command


@pytest.mark.parametrize(("offset_xy", "yaw"), [((0.0, 0.0), 0.0), ((0.03, -0.02), 0.2)])
def test_holds_a_cube_lifted_10_cm(pick, offset_xy, yaw):
    # As on the UR5e: the pinch point 8 mm above the cube centre, the fingertips off the table.
    result = pick(build, 0, offset_xy, yaw, -0.008)
    assert result["finite"]
    assert result["rise"] > 0.05, result
    assert result["drift"] < 0.01, result


def test_builder_refuses_a_record_it_cannot_build():
    arm = KINOVA_GEN3.arms[0]
    no_camera = dataclasses.replace(arm, hand_camera=None)
    with pytest.raises(ValueError, match="camera"):
        build_kinova_gen3(dataclasses.replace(KINOVA_GEN3, arms=(no_camera,)))
    six = dataclasses.replace(arm, joints=arm.joints[:6], home=arm.home[:6])
    with pytest.raises(ValueError, match="7 joints"):
        build_kinova_gen3(dataclasses.replace(KINOVA_GEN3, arms=(six,)))


def test_env_names_are_rmbs_and_derive_from_the_record():
    entry = ENVS["kinova_gen3_cable"]
    assert entry.env_attr == "MujocoKinovaGen3CableEnv"  # RMB's env class
    assert entry.gym_id == "rmb_lerobot/MujocoKinovaGen3Cable-v0"
    assert entry.lerobot_type == "rmb_kinova_gen3_cable" and entry.robot_type == "kinova_gen3"
    assert entry.cameras == ("front", "left", "right", "hand")
    assert entry.num_worlds == 6  # RMB's six pole positions
