"""rmb-convert to-lerobot: feature mapping, exact frame rate, LeRobot's own loader reads it."""

from __future__ import annotations

import json
import os
import stat
import tempfile
from fractions import Fraction
from pathlib import Path

import av
import h5py
import numpy as np
import pytest
import torch
from lerobot.configs import DepthEncoderConfig
from lerobot.datasets import dataset_writer, video_utils
from lerobot.datasets.lerobot_dataset import LeRobotDataset, LeRobotDatasetMetadata
from lerobot.scripts import lerobot_dataset_viz as viz

from rmb_lerobot import find_episodes, open_episode
from rmb_lerobot import keys as K
from rmb_lerobot import lerobot_names as N
from rmb_lerobot.converters import ConvertOptions, to_lerobot
from rmb_lerobot.converters.skip import skip_sequence
from rmb_lerobot.envs.lerobot_config import ENV_CONFIGS
from rmb_lerobot.pose import pose_to_policy

CAMERAS = ("front", "hand")  # what the demos fixture records
RATE = 31.25  # RMB's UR5e control rate: 0.004 s x frame_skip 8


def _load(root, **kwargs) -> LeRobotDataset:
    return LeRobotDataset(f"local/{root.name}", root=root, video_backend="pyav", **kwargs)


def test_dataset_keys_are_the_env_types_features_map_targets(demos, tmp_path):
    root = tmp_path / "insert"
    to_lerobot([demos], output=root, video_codec="h264", progress=False)
    meta = LeRobotDatasetMetadata("local/insert", root=root)
    env = ENV_CONFIGS["rmb_ur5e_insert"](cameras=list(CAMERAS), image_width=32, image_height=32)
    seen_by_policies = {k for k, ft in meta.features.items() if ft["dtype"] == "video"}
    assert seen_by_policies | {N.STATE, N.ACTION_KEY} == set(env.features_map.values())
    for raw, feature in env.features_map.items():
        assert tuple(meta.features[feature]["shape"]) == env.features[raw].shape
    assert meta.robot_type == "ur5e"
    assert meta.fps == RATE and meta.total_episodes == 2


def test_features_names_and_metadata(converted_depth, demos):
    meta = LeRobotDatasetMetadata("local/insert_depth", root=converted_depth)
    features = meta.features
    assert features[N.STATE]["names"][:2] == [
        "measured_joint_pos.joint_0",
        "measured_joint_pos.joint_1",
    ]
    assert features[N.STATE]["names"][-1] == "measured_joint_pos.gripper"
    assert meta.depth_keys == [N.depth_image_key(c) for c in CAMERAS]
    # Every other RMB key is its own feature; nothing is dropped.
    for key in ("measured_eef_pose", "command_eef_pose_rel", "measured_eef_wrench", "time"):
        assert N.rmb_feature_key(key) in features
    assert features["observation.eef_pose"]["names"] == ["x", "y", "z", "qw", "qx", "qy", "qz"]
    rmb = json.loads((converted_depth / N.RMB_METADATA_PATH).read_text())
    assert rmb["rate"]["source"] == {"hz": RATE, "fraction": "125/4"}
    assert rmb["state_keys"] == [K.MEASURED_JOINT_POS] and rmb["env"] == "MujocoUR5eInsertEnv"
    for entry, path in zip(rmb["episodes"], find_episodes(demos), strict=True):
        with open_episode(path) as ep:
            assert entry["source"] == path.name and entry["length"] == len(ep)
            assert entry["attrs"]["world_idx"] == ep.attrs["world_idx"]
            assert entry["attrs"]["hand_depth_image_fovy"] == ep.fovy("hand")
    modality = json.loads((converted_depth / N.GR00T_MODALITY_PATH).read_text())
    assert modality["state"]["arm"] == {"start": 0, "end": 6, "original_key": N.STATE}
    assert modality["action"]["gripper"]["end"] == 7 and modality["action"]["gripper"]["absolute"]
    assert set(modality["video"]) == set(CAMERAS)
    assert modality["annotation"]["human.task_description"] == {"original_key": "task_index"}


def test_lerobot_loads_it_at_the_exact_rate(converted_depth, demos):
    dataset = _load(converted_depth, delta_timestamps={N.ACTION_KEY: [i / RATE for i in range(5)]})
    path = find_episodes(demos)[1]
    with open_episode(path) as ep:
        length = len(ep)
        start = dataset.meta.episodes[1]["dataset_from_index"]
        for i in (0, length // 2, length - 1):
            item = dataset[start + i]
            assert item["timestamp"].item() == pytest.approx(i / RATE, abs=1e-6)
            assert item["time"].item() == pytest.approx(ep[K.TIME][i], abs=1e-6)
            np.testing.assert_array_equal(
                item[N.STATE].numpy(), ep[K.MEASURED_JOINT_POS][i].astype(np.float32)
            )
            expected = ep[K.COMMAND_JOINT_POS][i : i + 5].astype(np.float32)
            got = item[N.ACTION_KEY].numpy()[: len(expected)]
            np.testing.assert_array_equal(got, expected)
            assert item["task"] == ep.attrs[K.ATTR_TASK_DESC]
            rgb = (item[N.image_key("front")].permute(1, 2, 0).numpy() * 255).round()
            assert np.abs(rgb - ep["front_rgb_image"][i]).mean() < 12
            depth_mm = item[N.depth_image_key("hand")][0].numpy()
            assert np.abs(depth_mm - ep["hand_depth_image"][i] * 1000).max() <= _max_depth_error_mm(
                ep["hand_depth_image"][i]
            )


def _max_depth_error_mm(depth_m: np.ndarray) -> float:
    """Half of LeRobot's log quantisation step at the largest depth, plus mm rounding."""
    config = DepthEncoderConfig()
    span = np.log(config.depth_max + config.shift) - np.log(config.depth_min + config.shift)
    step_m = (float(depth_m.max()) + config.shift) * np.expm1(span / 4095)
    return 1000 * step_m / 2 + 0.5


def test_lerobot_dataset_viz_data_path_works(converted_depth):
    """What lerobot-dataset-viz does before drawing: DataLoader batches, CHW float frames."""
    dataset = _load(converted_depth, episodes=[1])
    loader = torch.utils.data.DataLoader(dataset, batch_size=16)
    frames = 0
    for batch in loader:
        for i in range(len(batch["index"])):
            for key in dataset.meta.camera_keys:
                if key in dataset.meta.depth_keys:
                    assert viz.to_hwc_float32_numpy(batch[key][i]).shape == (32, 32, 1)
                else:
                    assert viz.to_hwc_uint8_numpy(batch[key][i]).shape == (32, 32, 3)
            frames += 1
    assert frames == dataset.meta.episodes[1]["length"]
    assert viz.get_feature_names(dataset, N.ACTION_KEY)[0] == "command_joint_pos.joint_0"
    for key in dataset.meta.depth_keys:
        stats = dataset.meta.stats[key]
        assert 10 < float(np.asarray(stats["q01"]).item()) < float(np.asarray(stats["q99"]).item())


def test_skip_subsamples_like_rmb_and_divides_the_rate(demos, tmp_path):
    root = tmp_path / "skip2"
    to_lerobot(
        [demos], output=root, options=ConvertOptions(skip=2), video_codec="h264", progress=False
    )
    dataset = _load(root)
    assert dataset.fps == RATE / 2
    path = find_episodes(demos)[0]
    with open_episode(path) as ep:
        length = -(-len(ep) // 2)
        assert dataset.meta.episodes[0]["length"] == length
        rows = dataset.hf_dataset.with_format("numpy")[:length]
        rel = skip_sequence(K.COMMAND_JOINT_POS_REL, ep[K.COMMAND_JOINT_POS_REL][:], 2)
        np.testing.assert_allclose(rows["action.joint_pos_rel"], rel, atol=1e-6)
        np.testing.assert_array_equal(
            rows[N.STATE], ep[K.MEASURED_JOINT_POS][::2].astype(np.float32)
        )
        item = dataset[length - 1]
        assert item["timestamp"].item() == pytest.approx((length - 1) / (RATE / 2), abs=1e-6)


def test_eef_pose_state_uses_the_policy_view_and_keeps_the_raw_pose(demos, tmp_path):
    root = tmp_path / "eef"
    options = ConvertOptions(
        state_keys=(K.MEASURED_EEF_POSE, K.MEASURED_GRIPPER_JOINT_POS),
        action_keys=(K.COMMAND_EEF_POSE_REL, K.COMMAND_GRIPPER_JOINT_POS),
        camera_names=("hand",),
        task="put the peg in",
    )
    to_lerobot([demos], output=root, options=options, video_codec="h264", progress=False)
    dataset = _load(root)
    features = dataset.meta.features
    assert features[N.STATE]["shape"] == (10,) and features[N.ACTION_KEY]["shape"] == (7,)
    assert features[N.STATE]["names"][3:5] == ["measured_eef_pose.r00", "measured_eef_pose.r01"]
    assert N.image_key("front") not in features and N.image_key("hand") in features
    assert "observation.eef_pose" in features  # the exact pose, next to its policy view
    assert "action.eef_pose_rel" not in features  # in the action as recorded: not duplicated
    with open_episode(find_episodes(demos)[0]) as ep:
        item = dataset[3]
        policy = pose_to_policy(ep[K.MEASURED_EEF_POSE][3])
        np.testing.assert_allclose(item[N.STATE][:9].numpy(), policy, atol=1e-6)
        assert item["task"] == "put the peg in"


def test_each_video_states_the_true_frame_rate(converted_depth):
    info = json.loads((converted_depth / "meta" / "info.json").read_text())
    videos = {k: f for k, f in info["features"].items() if f["dtype"] == "video"}
    assert len(videos) == 4 and info["fps"] == RATE
    for key, feature in videos.items():
        assert feature["info"]["video.fps"] == RATE, key  # LeRobot wrote int(125/4) = 31
        video = info["video_path"].format(video_key=key, chunk_index=0, file_index=0)
        with av.open(str(converted_depth / video)) as container:
            assert container.streams.video[0].average_rate == Fraction(125, 4), key


def test_depth_stats_describe_the_stored_clamped_depth(tmp_path, record, caplog):
    """Beyond LeRobot's depth range (10 m) values are stored clamped; stats must say so.

    NaN/inf depth is refused by default (test_depth_checks.py); kept, it is stored clamped."""
    episode = record(tmp_path / "src" / "far.hdf5")
    with h5py.File(episode, "r+") as h5:
        depth = h5["front_depth_image"][()]
        depth[3, :4, :4] = 12.8
        depth[4, 0, 0] = np.inf
        depth[5, 0, 0] = np.nan
        h5["front_depth_image"][...] = depth
    root = tmp_path / "ds"
    options = ConvertOptions(camera_names=("front",), depth=True, allow_non_finite=True)
    to_lerobot([episode.parent], output=root, options=options, video_codec="h264", progress=False)
    key = N.depth_image_key("front")
    stats = json.loads((root / "meta" / "stats.json").read_text())[key]
    assert np.ravel(stats["max"])[0] == pytest.approx(10.0)  # not 12.8, not inf
    assert np.isfinite(np.ravel(stats["mean"])[0])
    assert np.ravel(stats["min"])[0] == pytest.approx(0.01)  # the no-data zeros, as stored
    stored_mm = _load(root)[3][key][0].numpy()
    assert stored_mm.max() == pytest.approx(10_000, abs=_max_depth_error_mm(np.array(10.0)))
    warned = [r.getMessage() for r in caplog.records if "beyond 10 m" in r.getMessage()]
    assert warned and "far.hdf5" in warned[0] and "18 depth values" in warned[0]


def test_files_are_shared_readable_under_the_umask(demos, tmp_path):
    previous = os.umask(0o022)
    try:
        root = tmp_path / "ds"
        to_lerobot([demos], output=root, video_codec="h264", progress=False)
    finally:
        os.umask(previous)
    modes = {p.relative_to(root): stat.S_IMODE(p.stat().st_mode) for p in root.rglob("*")}
    assert any(p.suffix == ".mp4" for p in modes)
    for path, mode in modes.items():
        expected = 0o755 if (root / path).is_dir() else 0o644
        assert mode == expected, f"{path}: {oct(mode)}"
    assert stat.S_IMODE(root.stat().st_mode) == 0o755


def test_library_temporaries_go_to_the_staging(demos, tmp_path, monkeypatch):
    """LeRobot joins episode videos through ``tempfile`` files: inside the staging, where a
    killed run's leftovers are found and removed, not in $TMPDIR."""
    seen = []
    original = video_utils.concatenate_video_files

    def spy(*args, **kwargs):
        seen.append(Path(tempfile.gettempdir()))
        return original(*args, **kwargs)

    monkeypatch.setattr(dataset_writer, "concatenate_video_files", spy)
    before = tempfile.tempdir
    root = tmp_path / "ds"
    to_lerobot([demos], output=root, options=ConvertOptions(camera_names=("hand",)), progress=False)
    assert seen and all(p.parent == tmp_path and p.name.startswith(".ds.tmp-") for p in seen)
    assert tempfile.tempdir == before


def test_a_lean_dataset_gives_policies_the_same_samples(demos, tmp_path):
    full, lean = tmp_path / "full", tmp_path / "lean"
    to_lerobot([demos], output=full, progress=False)
    to_lerobot([demos], output=lean, options=ConvertOptions(extra_keys=False), progress=False)
    lean_meta = LeRobotDatasetMetadata("local/lean", root=lean)
    policy_keys = {N.STATE, N.ACTION_KEY, *(N.image_key(c) for c in CAMERAS)}
    assert set(lean_meta.features) < set(LeRobotDatasetMetadata("local/full", root=full).features)
    assert {k for k in lean_meta.features if k.startswith(("observation", "action"))} == policy_keys
    # What ACT samples (an action chunk): the same tensors from both, frame for frame.
    delta = {N.ACTION_KEY: [i / RATE for i in range(8)]}
    a, b = _load(full, delta_timestamps=delta), _load(lean, delta_timestamps=delta)
    assert len(a) == len(b)
    for index in (0, 7, len(a) // 2, len(a) - 1):
        for key in policy_keys:
            assert torch.equal(a[index][key], b[index][key]), (index, key)
