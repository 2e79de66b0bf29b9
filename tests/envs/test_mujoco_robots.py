"""MuJoCo builds each robot from the record it is given, and refuses a model that lacks it."""

import dataclasses

import mujoco
import pytest

from rmb_lerobot.envs.mujoco.robots import build_robot_model, build_ur5e, check_model
from rmb_lerobot.envs.robots import UR5E, Gripper, Pose, mounted

ARM = UR5E.arms[0]


def with_arm(**changes) -> object:
    """The UR5e record with its arm changed."""
    return dataclasses.replace(UR5E, arms=(dataclasses.replace(ARM, **changes),))


@pytest.fixture(scope="module")
def ur5e():
    model = build_robot_model(UR5E)
    return model, model.spec.compile()


def test_the_ur5e_model_is_built_from_its_record(ur5e):
    model, compiled = ur5e
    (arm,) = model.arms
    assert arm.record is ARM and model.cameras == {"hand": "hand"}
    assert arm.arm_joints == ARM.joints and arm.gripper_ctrl_range == (0.0, 255.0)
    check_model(UR5E, model, compiled)  # every name of the record is in the model


def test_the_builder_takes_the_mount_and_home_of_the_record_it_is_given():
    record = with_arm(home=(0.0,) * 6)
    record = mounted(record, (-0.5, 0.2, 0.9))
    model = build_ur5e(record)
    compiled = model.spec.compile()
    data = mujoco.MjData(compiled)
    mujoco.mj_kinematics(compiled, data)
    assert data.body(ARM.root_frame).xpos.tolist() == pytest.approx([-0.5, 0.2, 0.9])
    assert model.arms[0].home_arm_qpos == (0.0,) * 6
    assert model.stand.pos[:2] == (-0.5, 0.2)
    check_model(record, model, compiled)


def test_a_model_built_from_another_record_is_refused(ur5e):
    model, compiled = ur5e
    with pytest.raises(ValueError, match="arm 0 was built from another record"):
        check_model(with_arm(home=(0.0,) * 6), model, compiled)


def test_a_record_naming_what_the_model_lacks_is_refused(ur5e):
    model, compiled = ur5e
    record = with_arm(
        tcp_frame="gripper/nowhere",
        gripper=Gripper(ARM.gripper.joints, open=0.0, closed=1.0, measured_scale=1.0),
    )
    arm = dataclasses.replace(model.arms[0], record=record.arms[0])
    bad = dataclasses.replace(model, arms=(arm,))
    with pytest.raises(ValueError) as error:
        check_model(record, bad, compiled)
    message = str(error.value)
    assert "disagrees with robot record 'ur5e'" in message
    assert "arm 0: no frame 'gripper/nowhere'" in message
    assert "range (0.0, 255.0), record (0.0, 1.0)" in message


def test_mounting_needs_one_position_per_arm():
    with pytest.raises(ValueError, match="1 arms, got 2 mounts"):
        mounted(UR5E, (0, 0, 0), (1, 0, 0))
    assert mounted(UR5E, (1, 2, 3)).arms[0].mount == Pose((1, 2, 3), ARM.mount.quat)


def test_robots_without_a_mujoco_model_are_named():
    with pytest.raises(ValueError, match="robot 'kuka' has no MuJoCo model; MuJoCo builds"):
        build_robot_model(dataclasses.replace(UR5E, name="kuka"))
