"""Robot records: the layout, joint vector and cameras follow from the arms."""

import dataclasses

import numpy as np
import pytest

from rmb_lerobot import keys as K
from rmb_lerobot.envs.robots import ROBOTS, UR5E, Arm, Gripper, HandCamera, Pose, Robot, robot_for


def _arm(name: str, joints: int, gripper: Gripper, camera: str | None = None) -> Arm:
    return Arm(
        name=name,
        joints=tuple(f"{name}_joint{i + 1}" for i in range(joints)),
        home=(0.0,) * joints,
        gripper=gripper,
        mount=Pose(),
        root_frame=f"{name}_root",
        eef_frame=f"{name}_flange",
        tcp_frame=f"{name}_tcp",
        hand_frame=f"{name}_hand",
        hand_camera=HandCamera(camera, Pose(), 60.0) if camera else None,
    )


ROBOTIQ = Gripper(joints=("finger",), open=0.0, closed=255.0, measured_scale=255 / 0.8)
PANDA_HAND = Gripper(joints=("finger1", "finger2"), open=1.0, closed=0.0, measured_scale=25.0)


def test_the_ur5e_record_is_rmbs_ur5e():
    assert robot_for("ur5e") is UR5E and ROBOTS["ur5e"] is UR5E
    assert UR5E.layout == K.UR5E_LAYOUT  # 6 joints + 1 gripper value, one eef
    assert UR5E.cameras == ("hand",)
    (arm,) = UR5E.arms
    assert arm.gripper.command_range == (0.0, 255.0) and arm.gripper.home_command == 0.0
    home = UR5E.home_command()
    assert home.shape == (7,) and home[-1] == 0.0
    assert home[:6] == pytest.approx(np.array([1.0, -0.5, -0.55, -0.45, 0.5, 0.5]) * np.pi)


def test_rmbs_other_mujoco_robots_are_records_with_rmbs_conventions():
    """xArm7 (7 joints + 0..255 gripper), Panda (7 + a 0..1 gripper that opens at 1) and the
    dual UR5e (two arms, left_hand/right_hand cameras): RMB's layouts and start poses."""
    xarm7, panda, dual = robot_for("xarm7"), robot_for("panda"), robot_for("ur5e_dual")
    assert xarm7.layout == K.RobotLayout(num_joints=8) and xarm7.cameras == ("hand",)
    assert xarm7.home_command().tolist() == [0.0, 0.0, 0.0, 0.8, 0.0, 0.8, 0.0, 0.0]
    assert xarm7.arms[0].gripper.command_range == (0.0, 255.0)
    assert panda.layout == K.RobotLayout(num_joints=8) and panda.cameras == ()
    assert panda.arms[0].gripper.command_range == (0.0, 1.0)
    assert panda.home_command()[-1] == 1.0  # starts open
    assert dual.layout == K.RobotLayout(num_joints=14, num_grippers=2, num_eefs=2)
    assert dual.cameras == ("left_hand", "right_hand")
    assert [arm.mount.pos[1] for arm in dual.arms] == [0.4, -0.4]  # left arm on +y
    # RMB's joint vector: per arm its joints, then its gripper value.
    assert dual.joint_slices() == ((slice(0, 6), 6), (slice(7, 13), 13))
    home = dual.home_command(((0.1,) * 6, (0.2,) * 6))
    assert home.tolist() == [0.1] * 6 + [0.0] + [0.2] * 6 + [0.0]
    # Each dual arm is the single UR5e's arm under its prefix.
    for arm in dual.arms:
        assert arm.joints == tuple(f"{arm.name}/{j}" for j in UR5E.arms[0].joints)
        assert arm.gripper.measured_scale == UR5E.arms[0].gripper.measured_scale


def test_a_new_robot_is_one_record():
    """What adding a robot takes: a record (here a made-up one) gives the layout, joint
    vector and cameras without touching anything else."""
    robot = Robot(
        "twin_xarm", "TwinXarm", (_arm("a", 7, ROBOTIQ, "a_hand"), _arm("b", 7, PANDA_HAND))
    )
    assert robot.layout == K.RobotLayout(num_joints=16, num_grippers=2, num_eefs=2)
    assert robot.cameras == ("a_hand",)
    assert robot.home_command().tolist() == [0.0] * 7 + [0.0] + [0.0] * 7 + [1.0]


def test_inconsistent_records_are_refused_with_the_reason():
    with pytest.raises(ValueError, match="arm 'arm': 6 joints but 5 home values"):
        dataclasses.replace(UR5E.arms[0], home=(0.0,) * 5)
    with pytest.raises(ValueError, match="camera names repeat"):
        Robot("twin", "Twin", (_arm("a", 6, ROBOTIQ, "hand"), _arm("b", 6, ROBOTIQ, "hand")))
    with pytest.raises(ValueError, match="has no arm"):
        Robot("none", "None", ())
    with pytest.raises(ValueError, match="open and closed values are both 1"):
        Gripper(joints=("f",), open=1.0, closed=1.0, measured_scale=1.0)
    with pytest.raises(ValueError, match=r"home pose \(0.0,\) has 1 values, expected 6"):
        UR5E.home_command(((0.0,),))
    with pytest.raises(ValueError, match=r"unknown robot 'kuka'; known: .*\bpanda, sawyer, ur5e\b"):
        robot_for("kuka")
    with pytest.raises(ValueError, match=r"joint_signs must be one \+1 or -1 per joint"):
        Gripper(joints=("l", "r"), open=0.05, closed=0.0, measured_scale=1.0, joint_signs=(1.0,))


def test_opposed_fingers_count_with_their_signs():
    """The WSG50's fingers move to (-g, +g): with the record's signs both count towards g."""
    from rmb_lerobot.envs.robots import SAWYER

    gripper = SAWYER.arms[0].gripper
    assert gripper.signs == (-1.0, 1.0)
    positions = (-0.03, 0.03)
    measured = (
        gripper.measured_scale
        * sum(s * q for s, q in zip(gripper.signs, positions, strict=True))
        / len(positions)
    )
    assert measured == pytest.approx(0.03)
    assert SAWYER.tactile_sensors == ("tactile_left", "tactile_right")
