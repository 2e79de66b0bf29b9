"""The key catalogue: RMB's names, dimensions and counterparts."""

import pytest

from rmb_lerobot import keys as K


def test_catalogue_holds_every_rmb_key_with_its_original_name():
    expected = {
        "time", "reward",
        "measured_joint_pos", "command_joint_pos", "measured_joint_vel", "command_joint_vel",
        "measured_joint_torque", "command_joint_torque",
        "measured_gripper_joint_pos", "command_gripper_joint_pos",
        "measured_eef_pose", "command_eef_pose", "measured_eef_vel", "command_eef_vel",
        "measured_eef_wrench", "command_eef_wrench",
        "measured_mobile_omni_vel", "command_mobile_omni_vel",
        "measured_joint_pos_rel", "command_joint_pos_rel",
        "measured_gripper_joint_pos_rel", "command_gripper_joint_pos_rel",
        "measured_eef_pose_rel", "command_eef_pose_rel",
    }  # fmt: skip
    assert set(K.KEYS) == expected
    assert K.MEASURED_EEF_POSE_REL in K.RELATIVE_KEYS
    assert set(K.MEASURED_KEYS) | set(K.COMMAND_KEYS) == expected - {"time", "reward"}


@pytest.mark.parametrize(
    ("key", "dim", "policy_dim"),
    [
        ("measured_joint_pos", 7, 7),
        ("command_joint_vel", 7, 7),
        ("measured_gripper_joint_pos", 1, 1),
        ("measured_eef_pose", 7, 9),  # policies see position + 6-D rotation
        ("command_eef_pose_rel", 6, 6),
        ("measured_eef_wrench", 6, 6),
        ("command_mobile_omni_vel", 3, 3),
        ("time", 0, 1),  # stored as (T,)
    ],
)
def test_dimensions_for_a_ur5e(key, dim, policy_dim):
    assert K.spec(key).dim(K.UR5E_LAYOUT) == dim
    assert K.spec(key).policy_dim(K.UR5E_LAYOUT) == policy_dim


def test_dimensions_scale_with_a_bimanual_layout():
    aloha = K.RobotLayout(num_joints=14, num_grippers=2, num_eefs=2)
    assert K.spec("measured_eef_pose").dim(aloha) == 14
    assert K.spec("measured_eef_pose").policy_dim(aloha) == 18
    assert K.spec("command_gripper_joint_pos").dim(aloha) == 2


def test_counterparts():
    assert K.measured_key("command_eef_pose_rel") == "measured_eef_pose_rel"
    assert K.command_key("measured_joint_pos") == "command_joint_pos"
    assert K.rel_key("measured_eef_pose") == "measured_eef_pose_rel"
    assert K.abs_key("command_gripper_joint_pos_rel") == "command_gripper_joint_pos"
    assert K.abs_key("command_joint_pos") == "command_joint_pos"
    with pytest.raises(KeyError, match="no relative variant"):
        K.rel_key("measured_joint_vel")
    with pytest.raises(KeyError, match="no measured/command pair"):
        K.measured_key("time")
    with pytest.raises(KeyError, match="unknown RMB key 'joint_pos'"):
        K.spec("joint_pos")


def test_camera_key_helpers():
    assert K.rgb_image_key("front") == "front_rgb_image"
    assert K.depth_image_key("hand") == "hand_depth_image"
    assert K.pointcloud_key("front") == "front_pointcloud"
    assert K.fovy_attr("front") == "front_depth_image_fovy"
    assert K.camera_pose_attr("front") == "front_depth_image_pose"
    assert K.camera_of("left_depth_image") == "left"
    assert K.is_image_key("right_rgb_image") and not K.is_image_key("front_pointcloud")
    assert K.camera_keys(["front", "hand"], depth=False) == ["front_rgb_image", "hand_rgb_image"]
    with pytest.raises(ValueError, match="not a camera key"):
        K.camera_of("measured_joint_pos")


def test_layout_for_env_knows_the_ur5e_envs_by_exact_name():
    assert K.layout_for_env("MujocoUR5eCableEnv") == K.UR5E_LAYOUT  # the original's and ours
    assert K.layout_for_env("RealUR5eDemoEnv") == K.UR5E_LAYOUT
    assert K.layout_for_env("MujocoUR5eCabinetHingeEnv") == K.UR5E_LAYOUT  # from our registry
    # Two arms, not a UR5e: 14 joints, two grippers, two eefs.
    assert K.layout_for_env("MujocoUR5eDualCableEnv") == K.RobotLayout(14, 2, 2)
    assert K.layout_for_env("RealUR5eDualDemoEnv") == K.RobotLayout(14, 2, 2)
    assert K.layout_for_env("MujocoXarm7CableEnv") == K.RobotLayout(num_joints=8)
    assert K.layout_for_env("MujocoPandaCableEnv") == K.RobotLayout(num_joints=8)
    assert K.layout_for_env("MujocoUR5eCable") is None  # RMB writes the class name with "Env"
    assert K.layout_for_env("MujocoXarm7DualCableEnv") is None  # no such robot record yet
    assert K.layout_for_env(None) is None and K.layout_for_env(b"MujocoUR5eCableEnv") is None
