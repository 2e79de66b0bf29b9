"""RMB's ALOHA built from Trossen's ViperX 300 kinematics: names, home, the URDF's joint
layout and limits, the mounts facing each other, wrist cameras, slide fingers, a grasp."""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np
import pytest

from rmb_lerobot.envs.mujoco.kinematics import ArmKinematics
from rmb_lerobot.envs.mujoco.models.aloha import JOINT_DYNAMICS, build_aloha
from rmb_lerobot.envs.mujoco.models.common import euler_quat
from rmb_lerobot.envs.mujoco.robots import MUJOCO_BUILDERS, check_model
from rmb_lerobot.envs.registry import ENVS
from rmb_lerobot.envs.robots import ALOHA, GripperKind
from rmb_lerobot.envs.robots.aloha import TABLE_TOP_Z, WRIST_CAMERA_POSE

RMB_JOINTS = ("waist", "shoulder", "elbow", "forearm_roll", "wrist_angle", "wrist_rotate")


def build():
    return build_aloha(ALOHA)


def test_names_home_and_layout_are_rmbs(at_home):
    robot, model, _ = at_home(build)
    check_model(ALOHA, robot, model)  # every name the record gives exists
    for arm, side in zip(robot.arms, ("left", "right"), strict=True):
        assert arm.arm_joints == tuple(f"{side}/{joint}" for joint in RMB_JOINTS)
        assert arm.gripper_joints == (f"{side}/left_finger", f"{side}/right_finger")
        assert arm.arm_actuators == arm.arm_joints  # RMB names the actuators as the joints
        assert arm.gripper_actuator == f"{side}/gripper"
        np.testing.assert_allclose(arm.home_arm_qpos, [0, -0.96, 1.16, 0, -0.3, 0])
        assert arm.gripper_ctrl_range == (0.002, 0.037) and arm.home_gripper == 0.037
        assert arm.record.gripper.kind is GripperKind.SLIDE
    assert ALOHA.layout.num_joints == 14 and ALOHA.command_size == 14  # RMB's 14-D action
    assert ALOHA.cameras == ("wrist_cam_left", "wrist_cam_right")
    assert (model.nu, model.nsensor, model.ncam) == (14, 4, 2)
    assert MUJOCO_BUILDERS["aloha"](ALOHA).name == "aloha"


def test_joint_limits_and_servo_gains_are_rmbs(at_home):
    _, model, _ = at_home(build)
    for side in ("left", "right"):
        for joint, (limits, *_, kp, force) in zip(RMB_JOINTS, JOINT_DYNAMICS, strict=True):
            name = f"{side}/{joint}"
            np.testing.assert_allclose(model.joint(name).range, limits)
            np.testing.assert_allclose(model.actuator(name).gainprm[0], kp)
            np.testing.assert_allclose(model.actuator(name).forcerange, (-force, force))
        np.testing.assert_allclose(model.joint(f"{side}/left_finger").range, (0.0, 0.041))
    # aloha_arms_config.xml: waist +-3.14158, shoulder -1.85005..1.25664, elbow
    # -1.76278..1.6057, wrist_angle -1.8675..2.23402.
    np.testing.assert_allclose(model.joint("left/shoulder").range, (-1.85005, 1.25664))
    np.testing.assert_allclose(model.joint("right/wrist_angle").range, (-1.8675, 2.23402))


def _arm_frame(data: mujoco.MjData, arm) -> tuple[np.ndarray, np.ndarray]:
    base = data.body(arm.root_body)
    return base.xpos.copy(), base.xmat.reshape(3, 3).copy()


@pytest.mark.parametrize("arm_index", [0, 1])
def test_forward_kinematics_match_the_vx300s_urdf(at_home, arm_index):
    robot, model, data = at_home(build)
    arm = robot.arms[arm_index]
    kin = ArmKinematics(model, arm)
    base_pos, base_mat = _arm_frame(data, arm)

    def in_base(name: str, q) -> np.ndarray:
        data.qpos[kin.qpos_index] = q
        mujoco.mj_kinematics(model, data)
        return base_mat.T @ (data.body(name).xpos - base_pos)

    prefix = arm.arm_joints[0].split("/")[0] + "/"
    # vx300s.urdf.xacro joint origins, summed: all joints at zero, the arm stretched along
    # the base's x axis: wrist_rotate at x = 0.05955 + 0.2 + 0.1 + 0.069744, z = 0.079 +
    # 0.04805 + 0.3 (within 1 mm).
    np.testing.assert_allclose(
        in_base(prefix + "gripper_link", np.zeros(6)), [0.429294, 0.0, 0.42705], atol=1e-3
    )
    # Shoulder at -pi/2 (axis y): the upper arm lies back along -x, the elbow 0.3 m behind
    # and 0.05955 m above the shoulder axis.
    elbow = in_base(prefix + "upper_forearm_link", [0, -np.pi / 2, 0, 0, 0, 0])
    np.testing.assert_allclose(elbow, [-0.3, 0.0, 0.12705 + 0.05955], atol=1e-3)
    # Waist at +pi/2 (axis z): the stretched arm points along the base's y axis.
    np.testing.assert_allclose(
        in_base(prefix + "gripper_link", [np.pi / 2, 0, 0, 0, 0, 0]),
        [0.0, 0.429294, 0.42705],
        atol=1e-3,
    )


def test_the_arms_face_each_other_across_the_table(at_home):
    robot, _, data = at_home(build)
    left, right = robot.arms
    (lpos, lmat), (rpos, rmat) = _arm_frame(data, left), _arm_frame(data, right)
    # aloha_arms_body.xml turned -90 deg: bases at y = +-0.469, x = -0.019, 2 cm over the top.
    np.testing.assert_allclose(lpos, [-0.019, 0.469, TABLE_TOP_Z + 0.02])
    np.testing.assert_allclose(rpos, [-0.019, -0.469, TABLE_TOP_Z + 0.02])
    np.testing.assert_allclose(lmat[:, 0], [0, -1, 0], atol=1e-12)  # left faces -y
    np.testing.assert_allclose(rmat[:, 0], [0, 1, 0], atol=1e-12)  # right faces +y
    # At home the two hands are mirror images over the table, above it.
    ltcp, rtcp = data.site(left.tcp_site).xpos, data.site(right.tcp_site).xpos
    np.testing.assert_allclose(ltcp * [1, -1, 1], rtcp, atol=1e-9)
    assert 0.1 < ltcp[2] - TABLE_TOP_Z < 0.4 and 0.1 < ltcp[1] < 0.3


def test_wrist_cameras_sit_where_rmbs_d405_does(at_home):
    robot, model, data = at_home(build)
    # RMB: gripper_base at (0.035, 0, 0) euler (0, 1.57, -1.57) in gripper_link, the camera at
    # (0, -0.0824748, -0.0095955) euler (2.70526, 0, 0) in gripper_base.
    base_quat = np.array(euler_quat((0.0, 1.57, -1.57)))
    base_mat = np.empty(9)
    mujoco.mju_quat2Mat(base_mat, base_quat)
    pos = np.array([0.035, 0, 0]) + base_mat.reshape(3, 3) @ [0, -0.0824748, -0.0095955]
    quat = np.empty(4)
    mujoco.mju_mulQuat(quat, base_quat, np.array(euler_quat((2.70525955359, 0.0, 0.0))))
    np.testing.assert_allclose(WRIST_CAMERA_POSE.pos, pos, atol=1e-4)
    np.testing.assert_allclose(np.abs(WRIST_CAMERA_POSE.quat @ quat), 1.0, atol=1e-4)
    for arm in robot.arms:
        camera = data.cam(arm.hand_camera)
        look = -camera.xmat.reshape(3, 3)[:, 2]
        to_tcp = data.site(arm.tcp_site).xpos - camera.xpos
        # It looks forward and down past the fingers: the pinch point is in its view.
        cos = look @ to_tcp / np.linalg.norm(to_tcp)
        assert cos > np.cos(np.deg2rad(model.cam(arm.hand_camera).fovy[0] / 2))


@pytest.mark.parametrize("arm_index", [0, 1])
def test_slide_fingers_open_and_close_to_the_command(sweep, arm_index):
    values = sweep(build(), arm_index, fractions=(0, 0.5, 1, 0))
    # Opening in metres, as commanded (nothing between the fingers): 0.002 .. 0.037.
    np.testing.assert_allclose(values, [0.002, 0.0195, 0.037, 0.002], atol=1e-3)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_ik_reaches_random_poses_it_can_reach(seed):
    robot = build()
    model = robot.spec.compile()
    rng = np.random.default_rng(seed)
    for arm in robot.arms:
        kin = ArmKinematics(model, arm)
        home = np.asarray(arm.home_arm_qpos)
        for _ in range(4):
            q = home + rng.uniform(-0.3, 0.3, 6)
            target = kin.fk(q)
            solution = kin.ik(target, home)
            assert solution.converged
            np.testing.assert_allclose(kin.fk(solution.qpos)[:3], target[:3], atol=1e-3)


def test_builder_refuses_a_record_it_cannot_build():
    arm = ALOHA.arms[0]
    seven = dataclasses.replace(arm, joints=(*arm.joints, "left/extra"), home=(*arm.home, 0.0))
    with pytest.raises(ValueError, match="6 joints and 2 fingers"):
        build_aloha(dataclasses.replace(ALOHA, arms=(seven, ALOHA.arms[1])))


def test_env_names_are_rmbs_and_derive_from_the_record():
    entry = ENVS["aloha_handover"]
    assert entry.env_attr == "MujocoAlohaHandoverEnv"  # RMB's env class
    assert entry.gym_id == "rmb_lerobot/MujocoAlohaHandover-v0"
    assert entry.lerobot_type == "rmb_aloha_handover" and entry.robot_type == "aloha"
    assert entry.cameras == ("overhead_cam", "worms_eye_cam", "wrist_cam_left", "wrist_cam_right")
    assert entry.num_worlds == 6
