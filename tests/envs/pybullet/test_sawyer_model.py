"""RMB's Sawyer + WSG50 + DIGIT model, built in code: what loads, where it is, how it moves.

Every expected value is re-typed from RMB's model and env code (the file and line in a comment),
not taken from the module under test, so the tests check the module against RMB.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pybullet as p
import pytest
from scipy.spatial.transform import Rotation

from rmb_lerobot.envs.pybullet import sawyer

# RMB: robo_manip_baselines/envs/assets/tacto/robots/sawyer/sawyer_wsg50.urdf, each joint's
# <origin xyz rpy> (line of the <joint>): base -> right_l6 -> right_hand -> gripper -> tips.
RMB_ARM_ORIGINS = [  # (xyz, rpy) of right_j0 .. right_j6 (lines 156, 223, 250, 277, 304, 344, 385)
    ((0, 0, 0.08), (0, 0, 0)),
    ((0.081, 0.05, 0.237), (-1.5708, 1.5708, 0)),
    ((0, -0.14, 0.1425), (1.5708, 0, 0)),
    ((0, -0.042, 0.26), (-1.5708, 0, 0)),
    ((0, -0.125, -0.1265), (1.5708, 0, 0)),
    ((0, 0.031, 0.275), (-1.5708, 0, 0)),
    ((0, -0.11, 0.1053), (-1.5708, -0.17453, 3.1416)),
]
RMB_RIGHT_HAND = ((0, 0, 0.0245), (0, 0, 1.5708))  # line 405
RMB_ARM_GRIPPER = ((0, 0, 0), (0, 0, 1.5708))  # line 791
RMB_GRIPPER_RIGHT_RPY = (0, 0, 3.14159)  # line 650, axis -x (line 653)
RMB_GUIDE_TO_FINGER = (0, 0, 0.023)  # lines 554, 702
RMB_FINGER_TO_TIP = (-0.006, 0, 0.08)  # lines 605, 747
# RMB: robo_manip_baselines/envs/tacto/TactoSawyerGraspEnv.py:16-28 (home) and
# TactoSawyerEnvBase.py:182-190 (base_position [0, 0, 0.1], fixed base).
RMB_HOME = [0, -1.24, -0.58, 2.18, 0.27, 0.7, 1]
RMB_HOME_GRIPPER = 0.02


def transform(xyz, rpy=(0, 0, 0)) -> np.ndarray:
    """4x4 homogeneous transform of a URDF <origin> (rpy = fixed-axis x, y, z)."""
    out = np.eye(4)
    out[:3, :3] = Rotation.from_euler("xyz", rpy).as_matrix()
    out[:3, 3] = xyz
    return out


def rot_z(angle: float) -> np.ndarray:
    return transform((0, 0, 0), (0, 0, angle))


def chain_to_eef(q) -> np.ndarray:
    """right_l6 in the root frame: joint origin, then the rotation about the joint's z axis."""
    pose = np.eye(4)
    for (xyz, rpy), angle in zip(RMB_ARM_ORIGINS, q, strict=True):
        pose = pose @ transform(xyz, rpy) @ rot_z(angle)
    return pose


def chain_to_tips(q, gripper: float) -> tuple[np.ndarray, np.ndarray]:
    """finger_left_tip and finger_right_tip in the root frame for fingers at (-g, +g)."""
    gripper_base = chain_to_eef(q) @ transform(*RMB_RIGHT_HAND) @ transform(*RMB_ARM_GRIPPER)
    to_tip = transform(RMB_GUIDE_TO_FINGER) @ transform(RMB_FINGER_TO_TIP)
    left = gripper_base @ transform((-gripper, 0, 0)) @ to_tip  # axis +x, position -g
    right_frame = gripper_base @ transform((0, 0, 0), RMB_GRIPPER_RIGHT_RPY)
    right = right_frame @ transform((-gripper, 0, 0)) @ to_tip  # axis -x, position +g
    return left, right


@pytest.fixture
def client():
    """A headless pybullet client with RMB's physics settings (TactoSawyerEnvBase.py:119-126)."""
    cid = p.connect(p.DIRECT)
    p.setPhysicsEngineParameter(
        numSolverIterations=200,
        solverResidualThreshold=1e-8,
        enableConeFriction=1,
        physicsClientId=cid,
    )
    p.setGravity(0, 0, -9.8, physicsClientId=cid)
    p.setTimeStep(0.005, physicsClientId=cid)
    yield cid
    p.disconnect(cid)


@pytest.fixture
def robot(client) -> sawyer.SawyerHandles:
    """The robot loaded RMB's way, at RMB's home pose."""
    handles = sawyer.load_sawyer_wsg50(client)
    sawyer.reset_joints(client, handles, RMB_HOME, RMB_HOME_GRIPPER)
    return handles


def link_frame(client: int, handles: sawyer.SawyerHandles, link: int) -> np.ndarray:
    """World 4x4 pose of a link's URDF frame (pybullet's ``worldLinkFrame``, not its COM)."""
    state = p.getLinkState(
        handles.body_id, link, computeForwardKinematics=True, physicsClientId=client
    )
    out = np.eye(4)
    out[:3, :3] = np.array(p.getMatrixFromQuaternion(state[5])).reshape(3, 3)
    out[:3, 3] = state[4]
    return out


def test_urdf_text_is_deterministic_and_written_atomically(tmp_path: Path):
    text = sawyer.sawyer_wsg50_urdf()
    assert text == sawyer.sawyer_wsg50_urdf()
    path = sawyer.write_sawyer_wsg50_urdf(tmp_path / "models")
    assert path == tmp_path / "models" / "sawyer_wsg50.urdf"
    assert path.read_text() == text
    assert [f.name for f in path.parent.iterdir()] == ["sawyer_wsg50.urdf"]  # no temp file left
    # Primitives only, except pybullet_data's own WSG50 base mesh (absolute path, it exists).
    assert text.count("<mesh ") == 2  # its visual and its collision
    assert str(sawyer.wsg50_mesh_path()) in text
    assert sawyer.wsg50_mesh_path().is_file()


def test_urdf_loads_headless_with_rmbs_names(client, robot):
    names = sawyer.joint_indices_by_name(robot.body_id, client)
    assert [j for j in names if j.startswith("right_j")] == [f"right_j{i}" for i in range(7)]
    assert robot.controlled_joints == tuple(
        names[n] for n in sawyer.ARM_JOINT_NAMES + sawyer.FINGER_JOINT_NAMES
    )
    # RMB's command order [q7, -g, +g] is pybullet's order of the movable joints.
    movable = [
        i
        for i in range(p.getNumJoints(robot.body_id, physicsClientId=client))
        if p.getJointInfo(robot.body_id, i, physicsClientId=client)[2] != p.JOINT_FIXED
    ]
    assert tuple(movable) == robot.controlled_joints
    links = sawyer.link_indices_by_name(robot.body_id, client)
    assert robot.fingertip_links == (links["finger_left_tip"], links["finger_right_tip"])
    assert robot.eef_link == links["right_l6"]
    assert robot.ft_joint == names["right_hand"]
    # RMB addresses the sensor links through their joints (TactoSawyerEnvBase.py:211-226).
    assert robot.fingertip_links == tuple(names[n] for n in sawyer.FINGERTIP_JOINT_NAMES)


def test_joint_types_axes_and_limits_are_rmbs(client, robot):
    def info(index: int):
        return p.getJointInfo(robot.body_id, index, physicsClientId=client)

    for index in robot.arm_joints:
        assert info(index)[2] == p.JOINT_REVOLUTE
        assert info(index)[13] == pytest.approx((0, 0, 1))  # every arm axis is z (lines 160-389)
    # sawyer_wsg50.urdf:161 (j0), 228 (j1), 255 (j2), 390 (j6).
    assert info(robot.arm_joints[0])[8:10] == pytest.approx((-3.0503, 3.0503))
    assert info(robot.arm_joints[1])[8:10] == pytest.approx((-3.8183, 2.2824))
    assert info(robot.arm_joints[2])[8:10] == pytest.approx((-3.0514, 3.0514))
    assert info(robot.arm_joints[6])[8:10] == pytest.approx((-4.7104, 4.7104))
    assert robot.arm_lower[4] == pytest.approx(-2.9842)  # line 309
    left, right = robot.finger_joints
    assert info(left)[2] == info(right)[2] == p.JOINT_PRISMATIC
    assert info(left)[13] == pytest.approx((1, 0, 0))  # line 505
    assert info(right)[13] == pytest.approx((-1, 0, 0))  # line 653
    assert info(left)[8:10] == pytest.approx((-0.055, -0.0027))  # line 500
    assert info(right)[8:10] == pytest.approx((0.0027, 0.055))  # line 649
    assert info(robot.ft_joint)[2] == p.JOINT_FIXED  # right_hand, line 405


def test_robot_sits_where_rmb_puts_it(client, robot):
    # pybulletX puts the base's centre of mass at (0, 0, 0.1); RMB's base link has its inertial
    # origin at (-0.1, 0, 0.07) (line 30), so the root link frame is at (0.1, 0, 0.03).
    base_com, _ = p.getBasePositionAndOrientation(robot.body_id, physicsClientId=client)
    assert base_com == pytest.approx((0.0, 0.0, 0.1), abs=1e-6)
    root = link_frame(client, robot, sawyer.link_indices_by_name(robot.body_id, client)["torso"])
    assert root[:3, 3] == pytest.approx((0.1, 0.0, 0.03), abs=1e-6)
    np.testing.assert_allclose(robot.root_position, (0.1, 0.0, 0.03), atol=1e-12)
    # Then, at home, the gripper hangs over the Insert board at (0.505, -0.03)
    # (TactoSawyerInsertEnv.py:71-73), which Insert's pre-motion grasps by going straight down.
    tips = [link_frame(client, robot, link) for link in robot.fingertip_links]
    centre = np.mean([tip[:3, :3] @ sawyer.PAD_CENTRE + tip[:3, 3] for tip in tips], axis=0)
    assert centre[:2] == pytest.approx((0.505, -0.03), abs=0.005)


def test_home_fk_matches_rmbs_joint_chain(client, robot):
    root = transform(sawyer.ROOT_POSITION)
    expected_eef = root @ chain_to_eef(RMB_HOME)
    np.testing.assert_allclose(link_frame(client, robot, robot.eef_link), expected_eef, atol=1e-6)
    expected_left, expected_right = chain_to_tips(RMB_HOME, RMB_HOME_GRIPPER)
    left, right = (link_frame(client, robot, link) for link in robot.fingertip_links)
    np.testing.assert_allclose(left, root @ expected_left, atol=1e-6)
    np.testing.assert_allclose(right, root @ expected_right, atol=1e-6)
    # The documented tool centre (mid-pads) in the eef frame.
    mid = np.mean([(t @ [*sawyer.PAD_CENTRE, 1])[:3] for t in (left, right)], axis=0)
    eef = link_frame(client, robot, robot.eef_link)
    np.testing.assert_allclose(eef[:3, :3] @ sawyer.TOOL_CENTRE_IN_EEF + eef[:3, 3], mid, atol=1e-4)


def test_fingertip_pads_face_each_other(client, robot):
    left, right = (link_frame(client, robot, link) for link in robot.fingertip_links)
    normal_left = left[:3, :3] @ sawyer.PAD_NORMAL  # the pad normal is the tip link's +x axis
    normal_right = right[:3, :3] @ sawyer.PAD_NORMAL
    assert normal_left @ normal_right == pytest.approx(-1.0, abs=1e-6)
    centre_left = left[:3, :3] @ sawyer.PAD_CENTRE + left[:3, 3]
    centre_right = right[:3, :3] @ sawyer.PAD_CENTRE + right[:3, 3]
    gap = (centre_right - centre_left) @ normal_left  # > 0: facing, not back to back
    # Each tip sits 0.006 m outside its finger's axis (RMB_FINGER_TO_TIP), its pad 0.020 inside.
    assert gap == pytest.approx(2 * (RMB_HOME_GRIPPER + 0.006 - sawyer.PAD_CENTRE[0]), abs=1e-6)
    assert gap == pytest.approx(0.012, abs=1e-6)
    # The pad is TACTO's DIGIT gel: 0.02 m across (link y) x 0.03 m along the finger (link z).
    pad = sawyer.pad_box()
    assert pad.size[1:] == pytest.approx(sawyer.PAD_SIZE)
    assert pad.xyz[0] + pad.size[0] / 2 == pytest.approx(sawyer.PAD_CENTRE[0])


def test_fingertips_carry_rmbs_friction_and_a_stiffer_contact(client, robot):
    for link in robot.fingertip_links:
        info = p.getDynamicsInfo(robot.body_id, link, physicsClientId=client)
        # (lateral, rolling, spinning): TactoSawyerEnvBase.py:213-221; (damping, stiffness):
        # stiffer than RMB's 30 / 300 so a grasped object stays in front of the gel.
        assert (info[1], info[6], info[7], info[8], info[9]) == pytest.approx(
            (1.2, 0.03, 0.03, 200.0, 10000.0)
        )


@pytest.mark.parametrize("gripper", [0.04, 0.015])
def test_fingers_follow_minus_g_plus_g_under_rmbs_position_control(client, robot, gripper):
    for _ in range(100):  # 0.5 s of RMB's 0.005 s substeps
        sawyer.apply_position_targets(client, robot, RMB_HOME, gripper)
        p.stepSimulation(physicsClientId=client)
    states = p.getJointStates(robot.body_id, robot.controlled_joints, physicsClientId=client)
    positions = np.array([s[0] for s in states])
    np.testing.assert_allclose(positions[7:], (-gripper, gripper), atol=2e-4)
    np.testing.assert_allclose(positions[:7], RMB_HOME, atol=1e-3)  # the arm holds its pose


def test_ft_sensor_reads_the_gripper_weight(client, robot):
    for _ in range(20):
        sawyer.apply_position_targets(client, robot, RMB_HOME, RMB_HOME_GRIPPER)
        p.stepSimulation(physicsClientId=client)
    # RMB's wrench: the reaction forces of joint right_hand (TactoSawyerEnvBase.py:351-352).
    wrench = p.getJointState(robot.body_id, robot.ft_joint, physicsClientId=client)[2]
    hand_mass = 1.2 + 6 * 0.1  # RMB: gripper base 1.2 kg, guides/fingers/tips 0.1 kg each
    assert np.linalg.norm(wrench[:3]) == pytest.approx(hand_mass * 9.8, rel=0.02)
