"""SART on a short scripted Insert demo: complete, valid episodes that converge onto the demo."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rmb_lerobot import keys as K
from rmb_lerobot import open_episode
from rmb_lerobot.augment import AugmentConfig, Augmenter, Region, derive_relative
from rmb_lerobot.envs.collect import CollectConfig, Collector
from rmb_lerobot.errors import RmbFormatError
from rmb_lerobot.pose import pose_to_matrix

REGION = Region(time_idx=29, radius=0.03, max_rotation_deg=6.0)
SAMPLES = 3
DURATION_S = 1.0


@pytest.fixture(scope="module")
def insert_demo(tmp_path_factory) -> Path:
    """One scripted Insert demonstration (world 2, hand + front cameras at 32x32, RGB only)."""
    config = CollectConfig(
        env="insert",
        out=tmp_path_factory.mktemp("demo"),
        episodes=1,
        world_idx=(2,),
        cameras=("front", "hand"),
        image_size=(32, 32),
        depth=False,
    )
    collector = Collector(config)
    try:
        result = collector.record(0)
    finally:
        collector.close()
    assert result.success
    return result.path


@pytest.fixture(scope="module")
def augmented(insert_demo, tmp_path_factory):
    out = tmp_path_factory.mktemp("augmented")
    config = AugmentConfig(samples_per_region=SAMPLES, duration_s=DURATION_S, seed=3)
    with Augmenter("MujocoUR5eInsert", insert_demo, out, config) as augmenter:
        targets = augmenter.sample_targets(REGION, 0)
        results = list(augmenter.run([REGION]))
        offset = augmenter.tool_offset
    return results, targets, offset


def test_every_sample_is_a_complete_rmb_episode(insert_demo, augmented):
    results, _, _ = augmented
    assert [(r.region, r.sample) for r in results] == [(0, i) for i in range(SAMPLES)]
    with open_episode(insert_demo) as demo:
        demo_keys, demo_len = set(demo.keys()), len(demo)
        demo_attrs = dict(demo.attrs)
    drive_steps = round(DURATION_S / 0.032)
    for result in results:
        assert result.path.name == f"{insert_demo.stem}_augmented_region000_{result.sample:02d}.rmb"
        with open_episode(result.path) as ep:
            ep.validate(frames=True)
            assert set(ep.keys()) == demo_keys
            assert len(ep) == result.steps == drive_steps + 1 + demo_len - REGION.end_idx - 1
            assert all(len(ep[key][:]) == len(ep) for key in ep if not K.is_image_key(key))
            assert ep["hand_rgb_image"][:].shape == (len(ep), 32, 32, 3)
            np.testing.assert_allclose(np.diff(ep[K.TIME][:]), 0.032, atol=1e-9)
            assert ep.attrs[K.ATTR_DEMO_NAME] == result.path.stem
            for attr in (K.ATTR_ENV, K.ATTR_WORLD_IDX, K.ATTR_TASK_DESC, K.ATTR_CAMERA_NAMES):
                assert ep.attrs[attr] == demo_attrs[attr]
            # Relative keys agree with the absolute ones everywhere, the join included.
            absolute = {k: ep[k][:] for k in ep if k in K.KEYS and not K.is_relative_key(k)}
            for key, rel in derive_relative(absolute).items():
                np.testing.assert_allclose(ep[key][:], rel, atol=1e-6, err_msg=key)


def test_the_first_frame_is_the_perturbed_pose(insert_demo, augmented):
    results, targets, offset = augmented
    with open_episode(insert_demo) as demo:
        centre = (pose_to_matrix(demo[K.COMMAND_EEF_POSE][REGION.time_idx]) @ offset)[:3, 3]
    for result, target in zip(results, targets, strict=True):
        # Samples lie on the sphere's surface, rotated within the region's bound.
        assert np.linalg.norm(target[:3, 3] - centre) == pytest.approx(REGION.radius, abs=1e-9)
        with open_episode(insert_demo) as demo:
            centre_rot = (pose_to_matrix(demo[K.COMMAND_EEF_POSE][REGION.time_idx]) @ offset)[
                :3, :3
            ]
        assert _angle_deg(centre_rot, target[:3, :3]) <= REGION.max_rotation_deg + 1e-6
        with open_episode(result.path) as ep:
            first = pose_to_matrix(ep[K.MEASURED_EEF_POSE][0]) @ offset
        # Frame 0 is the state the drive out ended in: at the sample, less the servo's sag
        # under the peg's weight (about 1.5 cm in this env).
        gap = np.linalg.norm(first[:3, 3] - target[:3, 3])
        assert gap == pytest.approx(result.target_error_m, abs=1e-9)
        assert gap < 0.025
        assert _angle_deg(first[:3, :3], target[:3, :3]) < 3.0


def _angle_deg(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.degrees(np.arccos(np.clip((np.trace(a.T @ b) - 1) / 2, -1.0, 1.0))))


def test_the_reversed_motion_joins_the_rest_of_the_demo_continuously(insert_demo, augmented):
    results, _, _ = augmented
    k = REGION.end_idx
    with open_episode(insert_demo) as demo:
        demo_joints = demo[K.MEASURED_JOINT_POS][:]
        demo_commands = demo[K.COMMAND_JOINT_POS][:]
        demo_hand = demo["hand_rgb_image"][:]
    demo_step = np.abs(np.diff(demo_joints, axis=0)).max()
    for result in results:
        assert result.replay_error_rad < 1e-6  # same machine: the replay is exact
        n = result.reversed_steps
        with open_episode(result.path) as ep:
            joints = ep[K.MEASURED_JOINT_POS][:]
            commands = ep[K.COMMAND_JOINT_POS][:]
            hand = ep["hand_rgb_image"][:]
        # The reversed motion ends where the demo was at the convergence step...
        np.testing.assert_allclose(joints[n - 1], demo_joints[k], atol=1e-9)
        # ...and the demo goes on from there: the step across the join is a demo-sized step.
        assert np.abs(joints[n] - joints[n - 1]).max() <= 1.5 * demo_step
        np.testing.assert_array_equal(joints[n:], demo_joints[k + 1 :])
        np.testing.assert_array_equal(commands[n:], demo_commands[k + 1 :])
        assert np.abs(hand[n:].astype(int) - demo_hand[k + 1 :]).mean() < 4  # video re-encoded
        # Along the reversed motion the arm moves smoothly towards the convergence pose.
        assert np.abs(np.diff(joints[:n], axis=0)).max() <= 1.5 * demo_step
        start_gap = np.abs(joints[0] - demo_joints[k]).max()
        assert start_gap > 0.01


def test_samples_are_reproducible_and_distinct(insert_demo, augmented, tmp_path):
    _, targets, _ = augmented
    config = AugmentConfig(samples_per_region=SAMPLES, duration_s=DURATION_S, seed=3)
    with Augmenter("insert", insert_demo, tmp_path, config) as again:
        for a, b in zip(again.sample_targets(REGION, 0), targets, strict=True):
            np.testing.assert_array_equal(a, b)
        other = again.sample_targets(REGION, 1)
    positions = [t[:3, 3] for t in targets + other]
    gaps = [np.linalg.norm(a - b) for i, a in enumerate(positions) for b in positions[i + 1 :]]
    assert min(gaps) > 1e-3


def test_the_demo_must_come_from_the_env_named(insert_demo, tmp_path):
    with pytest.raises(RmbFormatError, match="recorded in 'MujocoUR5eInsertEnv', not in"):
        Augmenter("door", insert_demo, tmp_path, AugmentConfig(samples_per_region=1))


def test_a_region_past_the_demo_is_refused_before_anything_is_written(insert_demo, tmp_path):
    config = AugmentConfig(samples_per_region=1, duration_s=DURATION_S)
    with (
        Augmenter("insert", insert_demo, tmp_path / "out", config) as augmenter,
        pytest.raises(RmbFormatError, match=r"time_idx must be a step of the demo"),
    ):
        list(augmenter.run([Region(time_idx=10_000, radius=0.02)]))
    assert not (tmp_path / "out").exists()


def test_existing_episodes_are_kept_unless_overwrite_is_asked(insert_demo, augmented, tmp_path):
    results, _, _ = augmented
    out = results[0].path.parent
    before = results[0].path.stat().st_mtime_ns
    config = AugmentConfig(samples_per_region=1, duration_s=DURATION_S, seed=3)
    with (
        Augmenter("insert", insert_demo, out, config) as augmenter,
        pytest.raises(RmbFormatError, match="destination exists"),
    ):
        list(augmenter.run([REGION]))
    assert results[0].path.stat().st_mtime_ns == before
