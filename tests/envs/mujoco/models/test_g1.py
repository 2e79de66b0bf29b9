"""RMB's Unitree G1 upper body from example-robot-data's URDF: names, fixed legs and waist, FK
against RMB's own G1 model numbers, limits, home over the bottles, head camera, hand synergy."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from rmb_lerobot.envs.mujoco.kinematics import ArmKinematics
from rmb_lerobot.envs.mujoco.models.g1 import FIXED_JOINTS, build_g1, finger_positions
from rmb_lerobot.envs.mujoco.robots import check_model
from rmb_lerobot.envs.mujoco.scene import TIMESTEP
from rmb_lerobot.envs.robots import G1
from rmb_lerobot.envs.robots.g1 import HEAD_QUAT, PELVIS_POS
from rmb_lerobot.envs.tasks.bottles import BOTTLE_XY, BottlesTask

# RMB's g1_body.xml (robots/g1): left arm body offsets from torso_link (pos, quat) and each
# joint's axis; torso_link sits at waist_roll_link, 44 mm up from the pelvis. The palm offset
# (41.5 mm along the wrist, 3 mm aside) is the URDF's hand_palm_joint.
TORSO = (-0.0039635, 0.0, 0.044)
LEFT_CHAIN = (
    ((0.0039563, 0.10022, 0.24778), (0.990264, 0.139201, 1.38722e-05, -9.86868e-05), "y"),
    ((0.0, 0.038, -0.013831), (0.990268, -0.139172, 0.0, 0.0), "x"),
    ((0.0, 0.00624, -0.1032), (1, 0, 0, 0), "z"),
    ((0.015783, 0.0, -0.080518), (1, 0, 0, 0), "y"),
    ((0.1, 0.00188791, -0.01), (1, 0, 0, 0), "x"),
    ((0.038, 0.0, 0.0), (1, 0, 0, 0), "y"),
    ((0.046, 0.0, 0.0), (1, 0, 0, 0), "z"),
)
PALM = (0.0415, 0.003, 0.0)
# RMB's joint ranges (g1_body.xml), left arm.
LEFT_LIMITS = (
    (-3.0892, 2.6704),
    (-1.5882, 2.2515),
    (-2.618, 2.618),
    (-1.0472, 2.0944),
    (-1.97222, 1.97222),
    (-1.61443, 1.61443),
    (-1.61443, 1.61443),
)
MIRROR = np.array([1, -1, -1, 1, -1, 1, -1])  # left -> right joint angles of the mirror pose


def rmb_palm(q: np.ndarray) -> np.ndarray:
    """Left palm origin in the pelvis frame from RMB's body offsets (independent of MuJoCo)."""
    pos, mat = np.array(TORSO), np.eye(3)
    for (offset, quat, axis), angle in zip(LEFT_CHAIN, q, strict=True):
        rot = np.empty(9)
        mujoco.mju_quat2Mat(rot, np.array(quat, dtype=float) / np.linalg.norm(quat))
        pos = pos + mat @ np.array(offset)
        mat = mat @ rot.reshape(3, 3)
        turn = np.empty(4)
        mujoco.mju_axisAngle2Quat(turn, np.eye(3)["xyz".index(axis)], angle)
        mujoco.mju_quat2Mat(rot, turn)
        mat = mat @ rot.reshape(3, 3)
    return pos + mat @ np.array(PALM)


@pytest.fixture(scope="module")
def g1():
    robot = build_g1(G1)
    model = robot.spec.compile()
    data = mujoco.MjData(model)
    for arm in robot.arms:
        arm.set_home(model, data)
    return robot, model, data


def test_names_actuators_and_layout_are_rmbs(g1):
    robot, model, _ = g1
    check_model(G1, robot, model)  # every name the record gives exists
    left, right = (arm.record for arm in robot.arms)
    assert left.joints[0] == "left_shoulder_pitch_joint"
    assert right.joints[-1] == "right_wrist_yaw_joint"
    assert left.gripper.joints == ("left_hand_middle_0_joint",)
    assert G1.layout.num_joints == 16 and G1.command_size == 16  # RMB's 16-D action
    # RMB names each actuator as its joint: 7 arm servos and the hand, per side.
    assert model.nu == 16
    assert {model.actuator(i).name for i in range(model.nu)} == set(
        left.joints + right.joints + left.gripper.joints + right.gripper.joints
    )
    assert robot.cameras == {"head": "head"} and G1.cameras == ("head",)


def test_legs_waist_and_pelvis_are_fixed_at_standing_height(g1):
    _, model, data = g1
    for name in FIXED_JOINTS:
        assert mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name) < 0
    pelvis = model.body("pelvis")
    assert model.body_jntnum[pelvis.id] == 0 and model.body_weldid[pelvis.id] == 0
    np.testing.assert_allclose(data.body("pelvis").xpos, PELVIS_POS)
    # Only the arms, hands and the task's objects move: 2 x (7 arm + 6 finger joints).
    assert model.njnt == 26


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_palm_follows_rmbs_g1_model_within_a_millimetre(g1, seed):
    robot, model, _ = g1
    left, right = (ArmKinematics(model, arm) for arm in robot.arms)
    rng = np.random.default_rng(seed)
    for _ in range(10):
        q = rng.uniform(left.lower, left.upper)
        np.testing.assert_allclose(left.fk(q)[:3], rmb_palm(q), atol=1e-3)
        # The right arm is the left one's mirror image in the pelvis's x-z plane (its joint
        # ranges are the mirrored ones: test_joint_limits_are_rmbs).
        mirrored = right.fk(q * MIRROR)[:3]
        np.testing.assert_allclose(mirrored, rmb_palm(q) * [1, -1, 1], atol=1e-3)


def test_joint_limits_are_rmbs(g1):
    robot, model, _ = g1
    left, right = (ArmKinematics(model, arm) for arm in robot.arms)
    np.testing.assert_allclose(np.column_stack([left.lower, left.upper]), LEFT_LIMITS, atol=1e-4)
    mirrored = np.sort(np.array(LEFT_LIMITS) * MIRROR[:, None], axis=1)
    np.testing.assert_allclose(np.column_stack([right.lower, right.upper]), mirrored, atol=1e-4)


def test_home_holds_each_open_hand_palm_down_over_its_bottle(g1):
    robot, _, data = g1
    table = BottlesTask().workspace.table
    for arm, (x, y) in zip(robot.arms, BOTTLE_XY, strict=True):
        grasp = data.site(arm.tcp_site).xpos
        assert np.hypot(grasp[0] - x, grasp[1] - y) < 0.06
        assert 0.2 < grasp[2] - table.top_z < 0.3  # above the 14 cm bottle
        palm_normal = data.site(arm.eef_site).xmat.reshape(3, 3)[:, 1]  # left palm faces -y
        down = -palm_normal if arm.record.name == "left" else palm_normal
        assert down[2] < -0.9
        assert data.joint(arm.gripper_joints[0]).qpos[0] == 0.0  # open


def test_head_camera_is_rmbs_and_looks_down_at_the_table(g1):
    _, model, data = g1
    quat = np.empty(4)
    mujoco.mju_euler2Quat(quat, np.array([0.0, -np.pi / 4, -np.pi / 2]), "xyz")
    np.testing.assert_allclose(HEAD_QUAT, quat, atol=1e-12)
    camera = model.camera("head")
    assert model.body(camera.bodyid[0]).name == "torso_link"
    np.testing.assert_allclose(camera.pos, (0.05, 0.0, 0.4))
    assert camera.fovy[0] == pytest.approx(62.0)
    forward = -data.cam("head").xmat.reshape(3, 3)[:, 2]  # MuJoCo cameras look along -z
    np.testing.assert_allclose(forward, [np.sqrt(0.5), 0.0, -np.sqrt(0.5)], atol=1e-6)


@pytest.mark.parametrize("side", ["left", "right"])
def test_one_command_closes_and_opens_the_whole_hand(side):
    robot = build_g1(G1)
    model = robot.spec.compile()
    model.opt.timestep = TIMESTEP  # the scene's
    data = mujoco.MjData(model)
    for arm in robot.arms:
        arm.set_home(model, data)
    arm = next(a for a in robot.arms if a.record.name == side)
    closed = arm.record.gripper.closed
    for target in (closed * 0.9, 0.0):
        data.actuator(arm.gripper_actuator).ctrl[0] = target
        mujoco.mj_step(model, data, nstep=250)  # 1 s
        hand = data.joint(arm.gripper_joints[0]).qpos[0]
        assert hand == pytest.approx(target, abs=0.05)
        assert arm.gripper_value(data) == pytest.approx(hand)  # RMB's hand value: the joint
        for joint, expected in finger_positions(side, hand).items():
            assert data.joint(joint).qpos[0] == pytest.approx(expected, abs=0.05), joint
