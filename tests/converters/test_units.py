"""Small pieces of the converters: frame rates, RMB's --skip, names, the mapping rules."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest

from rmb_lerobot import keys as K
from rmb_lerobot import lerobot_names as N
from rmb_lerobot.converters.components import component_names, infer_layout, split_by_prefix
from rmb_lerobot.converters.gr00t import modality
from rmb_lerobot.converters.lerobot_mapping import parse_key_dims, resolve_mapping
from rmb_lerobot.converters.rate import exact_rate, lerobot_fps, nominal_rate, same_rate
from rmb_lerobot.converters.schema import build_schema
from rmb_lerobot.converters.shards import split
from rmb_lerobot.converters.skip import skip_sequence
from rmb_lerobot.episode.timing import control_rate
from rmb_lerobot.pose import relative_pose, relative_pose_sequence


def test_rates_stay_exact():
    time = np.arange(300) / 31.25 + np.random.default_rng(0).normal(0, 2e-3, 300)  # jitter
    assert control_rate(time) == pytest.approx(31.25, rel=1e-3)
    assert nominal_rate(control_rate(time)) == Fraction(125, 4)
    assert nominal_rate("31.25") == nominal_rate("125/4") == Fraction(125, 4)
    assert nominal_rate(29.97) == 30 and nominal_rate(Fraction(125, 8)) == Fraction(125, 8)
    assert lerobot_fps(Fraction(125, 4)) == 31.25 and lerobot_fps(Fraction(30)) == 30
    assert isinstance(lerobot_fps(Fraction(30)), int)
    assert exact_rate(31.25) == Fraction(125, 4) and exact_rate(15.625) == Fraction(125, 8)
    assert nominal_rate(7.07) == Fraction(707, 100)  # no simple fraction near: kept
    assert same_rate(10.02, 9.98) and not same_rate(31.25, 30)


def test_skip_sums_joint_differences_and_composes_relative_poses(steps):
    joints = np.cumsum(np.random.default_rng(1).normal(size=(11, 7)), axis=0)
    rel = np.zeros_like(joints)
    rel[1:] = np.diff(joints, axis=0)
    skipped = skip_sequence(K.COMMAND_JOINT_POS_REL, rel, 3)
    # Group g covers steps 3g..3g+2: the change from step 3g-1 to 3g+2 (RMB's grouping).
    np.testing.assert_allclose(skipped[1], joints[5] - joints[2])
    np.testing.assert_allclose(skipped[-1], joints[10] - joints[8])  # last group zero-padded
    np.testing.assert_array_equal(skip_sequence(K.MEASURED_JOINT_POS, joints, 3), joints[::3])

    rng = np.random.default_rng(2)
    quats = rng.normal(size=(10, 4))
    poses = np.concatenate(
        [rng.normal(size=(10, 3)), quats / np.linalg.norm(quats, axis=1)[:, None]], 1
    )
    composed = skip_sequence(K.MEASURED_EEF_POSE_REL, relative_pose_sequence(poses), 4)
    assert composed.shape == (3, 6)
    np.testing.assert_allclose(composed[1], relative_pose(poses[3], poses[7]), atol=1e-9)
    np.testing.assert_allclose(composed[2], relative_pose(poses[7], poses[9]), atol=1e-9)


def test_component_names_follow_the_robot_layout():
    layout = infer_layout(
        {K.MEASURED_JOINT_POS: 7, K.MEASURED_GRIPPER_JOINT_POS: 1, K.MEASURED_EEF_POSE: 7}
    )
    assert layout == K.RobotLayout(num_joints=7, num_grippers=1, num_eefs=1)
    assert component_names(K.MEASURED_JOINT_POS, 7, layout, policy=True)[-2:] == [
        "joint_5",
        "gripper",
    ]
    assert component_names(K.MEASURED_EEF_POSE, 9, layout, policy=True)[3] == "r00"
    assert component_names(K.MEASURED_EEF_POSE, 7, layout, policy=False)[3] == "qw"
    assert component_names("custom_key", 2, layout, policy=False) == [
        "custom_key_0",
        "custom_key_1",
    ]
    assert split_by_prefix(
        ["measured_joint_pos.joint_0", "measured_joint_pos.gripper", "reward.reward"]
    ) == [
        ("measured_joint_pos", 2),
        ("reward", 1),
    ]
    assert split_by_prefix(["shoulder_pan.pos"]) is None


DUAL = K.RobotLayout(num_joints=14, num_grippers=2, num_eefs=2)  # RMB's dual UR5e


def test_a_dual_arm_joint_vector_is_named_arm_by_arm():
    """RMB orders a dual-arm joint vector per arm: left joints, left gripper, right ..."""
    assert DUAL.arm_groups() == ((range(0, 6), range(6, 7)), (range(7, 13), range(13, 14)))
    names = component_names(K.MEASURED_JOINT_POS, 14, DUAL, policy=False)
    assert names[5:8] == ["joint_5_0", "gripper_0", "joint_0_1"] and names[-1] == "gripper_1"
    assert component_names(K.COMMAND_GRIPPER_JOINT_POS, 2, DUAL, policy=False) == [
        "gripper_0",
        "gripper_1",
    ]
    assert component_names(K.MEASURED_EEF_POSE, 18, DUAL, policy=True)[9] == "x_1"


def test_gr00t_modality_describes_each_arm_of_a_dual_robot():
    schema = build_schema(
        {
            K.MEASURED_JOINT_POS: (5, 14),
            K.MEASURED_GRIPPER_JOINT_POS: (5, 2),
            K.COMMAND_JOINT_POS: (5, 14),
            K.COMMAND_EEF_POSE: (5, 14),
        },
        {},
        state_keys=[K.MEASURED_JOINT_POS],
        action_keys=[K.COMMAND_JOINT_POS, K.COMMAND_EEF_POSE],
        cameras=(),
        depth=False,
    )
    state = modality(schema, ["left", "right"])["state"]
    assert [(name, g["start"], g["end"]) for name, g in state.items()] == [
        ("left_arm", 0, 6),
        ("left_gripper", 6, 7),
        ("right_arm", 7, 13),
        ("right_gripper", 13, 14),
    ]
    action = modality(schema, ["left", "right"])["action"]
    assert action["right_eef_pose_position"] == {
        "start": 14 + 9,
        "end": 14 + 12,
        "original_key": N.ACTION_KEY,
        "absolute": True,
    }
    assert action["right_eef_pose_rotation"]["end"] == 14 + 18
    # Without the robot's arm names (a dataset of an unknown robot): numbered arms.
    assert list(modality(schema)["state"]) == ["arm_0", "gripper_0", "arm_1", "gripper_1"]
    # One arm keeps GR00T's single-arm names.
    single = build_schema(
        {K.MEASURED_JOINT_POS: (5, 8), K.MEASURED_GRIPPER_JOINT_POS: (5, 1)},
        {},
        [K.MEASURED_JOINT_POS],
        [],
        (),
        False,
    )
    assert list(modality(single)["state"]) == ["arm", "gripper"]


def test_feature_names_of_rmb_keys_round_trip():
    for key in K.KEYS:
        assert N.rmb_key_of_feature(N.rmb_feature_key(key)) == key
    assert N.rmb_feature_key(K.MEASURED_EEF_WRENCH) == "observation.eef_wrench"
    assert N.rmb_feature_key(K.COMMAND_EEF_POSE_REL) == "action.eef_pose_rel"
    assert (
        N.rmb_key_of_feature(N.STATE) is None and N.rmb_key_of_feature("observation.effort") is None
    )
    assert N.depth_image_key("front") == "observation.images.front_depth"


def test_default_mapping_of_a_foreign_dataset():
    features = {
        N.STATE: {"dtype": "float32", "shape": (6,), "names": ["a"] * 6},
        N.ACTION_KEY: {"dtype": "float32", "shape": (6,), "names": None},
        "observation.images.top": {"dtype": "video", "shape": (8, 8, 3)},
        "observation.images.top_depth": {"dtype": "video", "shape": (8, 8, 1)},
        "observation.joint_vel": {"dtype": "float32", "shape": (6,)},
        "next.reward": {"dtype": "float32", "shape": (1,)},
        "observation.environment_state": {"dtype": "float32", "shape": (3,)},
        "timestamp": {"dtype": "float32", "shape": (1,)},
    }
    mapping = resolve_mapping(features, ["observation.images.top_depth"], None)
    assert mapping.state == ((K.MEASURED_JOINT_POS, None),)
    assert mapping.action == ((K.COMMAND_JOINT_POS, None),)
    assert mapping.images == {
        "observation.images.top": "top_rgb_image",
        "observation.images.top_depth": "top_depth_image",
    }
    assert mapping.features == {
        "observation.joint_vel": K.MEASURED_JOINT_VEL,
        "next.reward": K.REWARD,
    }
    assert mapping.cameras() == ["top"]
    assert parse_key_dims(["a:2", "b"]) == (("a", 2), ("b", None))
    with pytest.raises(ValueError, match="KEY:DIM"):
        parse_key_dims(["a", "b"])


def test_workers_get_contiguous_slices():
    assert split(list(range(5)), 2) == [[0, 1], [2, 3, 4]]
    assert split(list(range(2)), 4) == [[0], [1]]
