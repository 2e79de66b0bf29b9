"""SART on a short scripted Insert demo: complete, valid episodes that converge onto the demo."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

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
            assert result.reversed_steps <= drive_steps + 1
            assert REGION.end_idx <= result.join_idx < demo_len - 1
            assert len(ep) == result.steps == result.reversed_steps + demo_len - result.join_idx - 1
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
    with open_episode(insert_demo) as demo:
        demo_joints = demo[K.MEASURED_JOINT_POS][:]
        demo_commands = demo[K.COMMAND_JOINT_POS][:]
        demo_hand = demo["hand_rgb_image"][:]
    demo_step = np.abs(np.diff(demo_joints, axis=0)).max()
    for result in results:
        assert result.replay_error_rad < 1e-6  # same machine: the replay is exact
        n, j = result.reversed_steps, result.join_idx
        with open_episode(result.path) as ep:
            joints = ep[K.MEASURED_JOINT_POS][:]
            commands = ep[K.COMMAND_JOINT_POS][:]
            hand = ep["hand_rgb_image"][:]
        # The reversed motion ends within a demo step of the demo step it joins at...
        assert np.abs(joints[n - 1] - demo_joints[j]).max() <= demo_step
        # ...and the demo goes on from there: the step across the join is a demo-sized step.
        assert np.abs(joints[n] - joints[n - 1]).max() <= 1.5 * demo_step
        np.testing.assert_array_equal(joints[n:], demo_joints[j + 1 :])
        np.testing.assert_array_equal(commands[n:], demo_commands[j + 1 :])
        assert np.abs(hand[n:].astype(int) - demo_hand[j + 1 :]).mean() < 4  # video re-encoded
        # Along the reversed motion the arm moves smoothly towards the convergence pose.
        assert np.abs(np.diff(joints[:n], axis=0)).max() <= 1.5 * demo_step
        start_gap = np.abs(joints[0] - demo_joints[REGION.end_idx]).max()
        assert start_gap > 0.01


# Several sampling seeds, two samples each: the join is checked key by key on every episode.
JOIN_SEEDS = (1, 2, 5)


@pytest.fixture(scope="module", params=JOIN_SEEDS, ids=lambda seed: f"seed{seed}")
def augmented_seed(request, insert_demo, tmp_path_factory):
    out = tmp_path_factory.mktemp(f"join{request.param}")
    config = AugmentConfig(samples_per_region=2, duration_s=DURATION_S, seed=request.param)
    with Augmenter("insert", insert_demo, out, config) as augmenter:
        return list(augmenter.run([REGION]))


COMMAND_KEYS = (K.COMMAND_JOINT_POS, K.COMMAND_GRIPPER_JOINT_POS, K.COMMAND_EEF_POSE)


def test_commands_run_on_into_the_demo_without_holding(insert_demo, augmented_seed):
    """Where the advanced reversed commands run out, the demo's own commands from the
    convergence step take over (stretched up to the join step), so no frame before the join
    commands "stay here" and the command stream carries straight on into the demo."""
    with open_episode(insert_demo) as demo:
        demo_cmd = {key: demo[key][:] for key in COMMAND_KEYS}
    arm = slice(0, 6)  # UR5e arm joints (the gripper is held closed on the peg throughout)
    demo_arm_step = np.abs(np.diff(demo_cmd[K.COMMAND_JOINT_POS][:, arm], axis=0)).max()
    for result in augmented_seed:
        n, j, fill = result.reversed_steps, result.join_idx, result.demo_commands_from
        assert result.command_shift > 0
        assert 1 <= fill < n  # some reversed frames ran out of commands before the join
        with open_episode(result.path) as ep:
            cmd = {key: ep[key][:] for key in COMMAND_KEYS}
        # At and after the join: exactly the demo's commands from the join step on.
        for key in COMMAND_KEYS:
            np.testing.assert_allclose(cmd[key][n - 1], demo_cmd[key][j], atol=1e-9, err_msg=key)
            np.testing.assert_array_equal(cmd[key][n:], demo_cmd[key][j + 1 :], err_msg=key)
        # The filled frames run the demo's commands forward from the one before the convergence
        # step (the drive's start) to the join step's: never held, always closer to the join's.
        joints = cmd[K.COMMAND_JOINT_POS][fill - 1 : n + 2, arm]
        steps = np.abs(np.diff(joints, axis=0)).max(axis=1)
        assert steps.min() > 1e-6, "a command is held across the join"
        assert steps.max() <= 1.5 * demo_arm_step
        to_join = np.abs(joints[:-2] - demo_cmd[K.COMMAND_JOINT_POS][j, arm]).max(axis=1)
        assert np.all(np.diff(to_join) < 0)
        np.testing.assert_allclose(
            cmd[K.COMMAND_GRIPPER_JOINT_POS][fill:n],
            np.repeat(demo_cmd[K.COMMAND_GRIPPER_JOINT_POS][j][None], n - fill, axis=0),
            atol=1e-9,
        )


def test_relative_keys_are_the_differences_across_the_join(augmented_seed):
    for result in augmented_seed:
        with open_episode(result.path) as ep:
            absolute = {k: ep[k][:] for k in ep if k in K.KEYS and not K.is_relative_key(k)}
            derived = derive_relative(absolute)
            assert set(derived) >= {
                K.COMMAND_JOINT_POS_REL,
                K.COMMAND_GRIPPER_JOINT_POS_REL,
                K.COMMAND_EEF_POSE_REL,
                K.MEASURED_JOINT_POS_REL,
            }
            for key, rel in derived.items():
                np.testing.assert_allclose(ep[key][:], rel, atol=1e-6, err_msg=key)
            # command_joint_vel is the commands' difference over the step up to the demo's
            # remainder (where the demo's own recording is kept as it is).
            c = absolute[K.COMMAND_JOINT_POS][: result.reversed_steps + 2]
            np.testing.assert_allclose(
                ep[K.COMMAND_JOINT_VEL][1 : len(c)], (c[1:] - c[:-1]) / 0.032, atol=1e-6
            )


def test_the_arm_does_not_back_out_of_the_demo_before_the_join(insert_demo, augmented_seed):
    """Driving out starts while the arm still moves down the demo's path (its commands lead it
    by the controller's lag); played backwards, that carry-on would lift the peg back up the
    path just before the demo descends again. It is cut: the reversed motion ends on the demo's
    path a few steps past the convergence step, and the demo resumes from there."""
    drive_steps = round(DURATION_S / 0.032)
    with open_episode(insert_demo) as demo:
        demo_tool = demo[K.MEASURED_EEF_POSE][:, :3]
    for result in augmented_seed:
        n, j = result.reversed_steps, result.join_idx
        step = np.linalg.norm(demo_tool[j + 1] - demo_tool[j])
        with open_episode(result.path) as ep:
            tool = ep[K.MEASURED_EEF_POSE][:, :3]
        assert n < drive_steps + 1 and j > REGION.end_idx  # a carry-on was found and cut
        assert np.linalg.norm(tool[n - 1] - demo_tool[j]) <= step


@pytest.mark.parametrize("carry_on", [0, 1, 3, 5])
def test_the_join_is_where_the_carry_on_along_the_demo_ends(insert_demo, tmp_path, carry_on):
    """A made-up drive out that follows the demo's path for ``carry_on`` steps and then leaves
    sideways: the reversed motion is cut where it left the path and joins the demo there."""
    k = REGION.end_idx
    with Augmenter("insert", insert_demo, tmp_path, AugmentConfig(samples_per_region=1)) as aug:
        demo_tool = aug.data[K.MEASURED_EEF_POSE][:, :3]
        on_path = demo_tool[k : k + carry_on + 1]
        away = on_path[-1] + np.outer(np.arange(1, 20), [0.0, 0.01, 0.0])
        forward = np.concatenate([on_path, away])
        poses = np.concatenate([forward, np.tile([1.0, 0, 0, 0], (len(forward), 1))], axis=1)
        cut, join = aug.find_join({K.MEASURED_EEF_POSE: poses[::-1]}, k)
    assert join == k + carry_on
    assert cut == len(forward) - 1 - carry_on  # the reversed frame of forward step carry_on


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


def test_a_shifted_demo_is_restored_with_its_shift_and_seed(tmp_path):
    """A demo collected with a random object shift: the augmenter places the objects as the
    demo had them when given the demo's shift and reset seed, and not without the shift."""
    config = CollectConfig(
        env="insert",
        out=tmp_path / "demo",
        episodes=1,
        world_idx=(2,),
        cameras=("hand",),
        image_size=(32, 32),
        depth=False,
        random_shift=0.02,
        seed=7,
    )
    collector = Collector(config)
    try:
        result = collector.record(0)
        demo_offset = collector.env.world_offset.copy()
    finally:
        collector.close()
    assert result.success and not result.failures  # reset with seed 7 + episode 0
    offsets = {}
    for shift in (0.02, 0.0):
        augment = AugmentConfig(samples_per_region=1, seed=7, random_shift=shift)
        with Augmenter("insert", result.path, tmp_path / "aug", augment) as augmenter:
            augmenter._restore(REGION.time_idx)
            offsets[shift] = augmenter.env.world_offset.copy()
    np.testing.assert_array_equal(offsets[0.02], demo_offset)
    assert np.abs(offsets[0.0] - demo_offset).max() > 1e-3  # the world's unshifted scene
    with pytest.raises(ValueError, match="random_shift must be >= 0"):
        AugmentConfig(samples_per_region=1, random_shift=-0.01)


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


def test_demo_values_at_fractional_steps():
    from rmb_lerobot.augment.sart import demo_at

    joints = np.array([[0.0, 1.0], [1.0, 3.0], [2.0, 5.0]])
    np.testing.assert_allclose(
        demo_at(joints, np.array([0.0, 0.5, 1.25, 2.0])),
        [[0.0, 1.0], [0.5, 2.0], [1.25, 3.5], [2.0, 5.0]],
    )
    # Poses: positions linear, quaternions on the short arc (q and -q are one rotation).
    quat = Rotation.from_euler("z", [[0.0], [90.0]], degrees=True).as_quat(scalar_first=True)
    quat[1] *= -1
    poses = np.concatenate([[[0.0, 0, 0], [1.0, 0, 0]], quat], axis=1)
    mid = demo_at(poses, np.array([0.5]), pose=True)[0]
    np.testing.assert_allclose(mid[:3], [0.5, 0, 0])
    angle = Rotation.from_quat(mid[3:], scalar_first=True).as_euler("xyz", degrees=True)
    np.testing.assert_allclose(angle, [0.0, 0.0, 45.0], atol=1e-9)
