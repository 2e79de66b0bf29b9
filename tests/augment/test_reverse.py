"""Playing a recording backwards: every key reversed as its meaning dictates."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from rmb_lerobot import keys as K
from rmb_lerobot.augment import derive_relative, invert_rel_pose, reverse_recording
from rmb_lerobot.errors import RmbFormatError
from rmb_lerobot.pose import apply_relative_pose, pose_to_matrix, rel_pose_to_matrix

T = 15


def _recording(seed: int) -> dict[str, np.ndarray]:
    """A random but smooth forward recording with absolute keys and their derived _rel keys."""
    rng = np.random.default_rng(seed)
    joints = np.cumsum(rng.normal(0, 0.05, (T, 7)), axis=0)
    positions = np.cumsum(rng.normal(0, 0.01, (T, 3)), axis=0)
    rotations = Rotation.from_rotvec(np.cumsum(rng.normal(0, 0.1, (T, 3)), axis=0))
    poses = np.concatenate([positions, rotations.as_quat(scalar_first=True)], axis=1)
    data = {
        K.TIME: 0.032 * np.arange(T),
        K.REWARD: rng.uniform(size=T),
        K.MEASURED_JOINT_POS: joints,
        K.COMMAND_JOINT_POS: joints + 0.01,
        K.MEASURED_GRIPPER_JOINT_POS: joints[:, 6:],
        K.MEASURED_EEF_POSE: poses,
        K.COMMAND_EEF_POSE: poses[::-1].copy(),
        K.MEASURED_JOINT_VEL: rng.normal(size=(T, 7)),
        K.MEASURED_EEF_WRENCH: rng.normal(size=(T, 6)),
        "hand_rgb_image": rng.integers(0, 255, (T, 4, 4, 3), dtype=np.uint8),
    }
    data[K.COMMAND_JOINT_VEL] = np.vstack([np.zeros(7), np.diff(data[K.COMMAND_JOINT_POS], axis=0)])
    data.update(derive_relative(data))
    return data


def _compose(start: np.ndarray, rels: np.ndarray) -> np.ndarray:
    pose = start
    for rel in rels[1:]:
        pose = apply_relative_pose(pose, rel)
    return pose


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_relative_keys_negate_and_eef_rel_poses_invert(seed):
    forward = _recording(seed)
    backward = reverse_recording(forward)
    rel = forward[K.MEASURED_JOINT_POS_REL]
    # Step s of the reversed recording undoes forward step T - s; step 0 is zero as RMB records.
    np.testing.assert_allclose(backward[K.MEASURED_JOINT_POS_REL][1:], -rel[:0:-1])
    np.testing.assert_array_equal(backward[K.MEASURED_JOINT_POS_REL][0], 0.0)
    eef_rel = forward[K.MEASURED_EEF_POSE_REL]
    for s in range(1, T):
        back = backward[K.MEASURED_EEF_POSE_REL][s]
        product = rel_pose_to_matrix(eef_rel[T - s]) @ rel_pose_to_matrix(back)
        np.testing.assert_allclose(product, np.eye(4), atol=1e-9)
    np.testing.assert_allclose(invert_rel_pose(invert_rel_pose(eef_rel)), eef_rel, atol=1e-9)
    # Velocities flip, absolute values and images run backwards, time is left as recorded.
    np.testing.assert_array_equal(
        backward[K.MEASURED_JOINT_VEL], -forward[K.MEASURED_JOINT_VEL][::-1]
    )
    np.testing.assert_array_equal(
        backward[K.MEASURED_EEF_WRENCH], forward[K.MEASURED_EEF_WRENCH][::-1]
    )
    np.testing.assert_array_equal(backward["hand_rgb_image"], forward["hand_rgb_image"][::-1])
    np.testing.assert_array_equal(backward[K.REWARD], forward[K.REWARD][::-1])
    np.testing.assert_array_equal(backward[K.TIME], forward[K.TIME])


@pytest.mark.parametrize("shift", [0, 1, 4])
@pytest.mark.parametrize("seed", [0, 3])
def test_reversed_relative_keys_agree_with_the_reversed_absolute_keys(seed, shift):
    """The algebra gives exactly the differences of the reversed absolute values, with command
    keys advanced by ``shift`` steps (held at the convergence value where they run out)."""
    forward = _recording(seed)
    backward = reverse_recording(forward, command_shift=shift)
    index = np.clip(T - 1 - np.arange(T) - shift, 0, T - 1)
    np.testing.assert_array_equal(
        backward[K.COMMAND_JOINT_POS], forward[K.COMMAND_JOINT_POS][index]
    )
    np.testing.assert_array_equal(
        backward[K.MEASURED_JOINT_POS], forward[K.MEASURED_JOINT_POS][::-1]
    )
    recomputed = derive_relative({k: v for k, v in backward.items() if not K.is_relative_key(k)})
    for key, values in recomputed.items():
        np.testing.assert_allclose(backward[key], values, atol=1e-9, err_msg=key)
    c = backward[K.COMMAND_JOINT_POS]
    np.testing.assert_allclose(backward[K.COMMAND_JOINT_VEL][1:], c[1:] - c[:-1], atol=1e-12)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_forward_then_reversed_path_returns_to_the_start(seed):
    forward = _recording(seed)
    backward = reverse_recording(forward)
    for key in (K.MEASURED_EEF_POSE, K.COMMAND_EEF_POSE):
        rel = forward[K.rel_key(key)]
        end = _compose(forward[key][0], rel)
        np.testing.assert_allclose(pose_to_matrix(end), pose_to_matrix(forward[key][-1]), atol=1e-9)
        back = _compose(end, backward[K.rel_key(key)])
        np.testing.assert_allclose(pose_to_matrix(back), pose_to_matrix(forward[key][0]), atol=1e-9)
    joints = forward[K.MEASURED_JOINT_POS]
    there = joints[0] + forward[K.MEASURED_JOINT_POS_REL].sum(axis=0)
    np.testing.assert_allclose(there + backward[K.MEASURED_JOINT_POS_REL].sum(axis=0), joints[0])


def test_a_key_without_a_reversal_rule_is_refused():
    with pytest.raises(RmbFormatError, match=r"no reversal rule.*'mystery_signal'"):
        reverse_recording({K.TIME: np.arange(3.0), "mystery_signal": np.zeros(3)})
    with pytest.raises(RmbFormatError, match="different lengths"):
        reverse_recording({K.TIME: np.arange(3.0), K.REWARD: np.zeros(4)})
