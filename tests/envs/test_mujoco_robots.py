"""MuJoCo builds each robot from its record, and refuses a model that disagrees with it."""

import dataclasses

import pytest

from rmb_lerobot.envs.mujoco.robots import build_robot_model, build_ur5e, check_model
from rmb_lerobot.envs.robots import UR5E, Gripper


def test_the_ur5e_model_agrees_with_its_record():
    model = build_robot_model(UR5E)
    (arm,) = model.arms
    assert arm.arm_joints == UR5E.arms[0].joints and model.cameras == {"hand": "hand"}
    assert arm.gripper_ctrl_range == UR5E.arms[0].gripper.command_range


def test_a_model_that_disagrees_with_the_record_is_refused():
    model = build_ur5e()
    arm = UR5E.arms[0]
    other = dataclasses.replace(
        UR5E,
        arms=(
            dataclasses.replace(
                arm,
                home=(0.0,) * 6,
                gripper=Gripper(arm.gripper.joints, open=0.0, closed=1.0, measured_scale=1.0),
            ),
        ),
    )
    with pytest.raises(ValueError) as error:
        check_model(other, model)
    message = str(error.value)
    assert "disagrees with robot record 'ur5e'" in message
    for fact in ("arm 0 home", "arm 0 gripper range", "arm 0 gripper scale"):
        assert fact in message


def test_robots_without_a_mujoco_model_are_named():
    with pytest.raises(ValueError, match="robot 'kuka' has no MuJoCo model; MuJoCo builds"):
        build_robot_model(dataclasses.replace(UR5E, name="kuka"))
