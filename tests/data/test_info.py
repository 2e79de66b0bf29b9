"""rmb-data info: what an episode holds, and RMB's statistics over episodes."""

import numpy as np
import pytest

from rmb_lerobot import keys as K
from rmb_lerobot import open_episode
from rmb_lerobot.data.info import collect_info, episode_info, format_info, summary


@pytest.mark.parametrize("name", ["ep.rmb", "ep.hdf5"])
def test_info_lists_keys_shapes_dtypes_and_ranges(tmp_path, record, name):
    path = record(tmp_path / name)
    info = episode_info(path)
    assert info["steps"] == 12 and info["fps"] == pytest.approx(31.25)
    assert info["attrs"][K.ATTR_TASK_DESC].startswith("Reach")
    assert info["keys"]["front_rgb_image"] == {"shape": [12, 48, 64, 3], "dtype": "uint8"}
    assert info["keys"]["hand_depth_image"]["shape"] == [12, 48, 64]
    joints = info["keys"][K.MEASURED_JOINT_POS]
    assert joints["shape"] == [12, 7] and joints["dtype"] == "float64"
    with open_episode(path) as ep:
        q = ep[K.MEASURED_JOINT_POS][:]
    assert joints["min"] == q.min() and joints["max"] == q.max()
    assert joints["min_per_dim"] == q.min(axis=0).tolist()
    assert joints["max_per_dim"] == q.max(axis=0).tolist()
    assert info["success_once"] and info["success_last"]  # the synthetic reward ends at 1
    text = format_info(info)
    assert "31.25 Hz" in text and "measured_joint_pos" in text and "(12, 48, 64, 3)" in text


def test_image_ranges_only_when_asked(tmp_path, record):
    path = record(tmp_path / "ep.rmb")
    assert "min" not in episode_info(path)["keys"]["front_depth_image"]
    depth = episode_info(path, image_stats=True)["keys"]["front_depth_image"]
    with open_episode(path) as ep:
        stored = ep["front_depth_image"][:]
    assert depth["min"] == pytest.approx(stored.min()) and depth["max"] == pytest.approx(
        stored.max()
    )
    assert 0 < depth["min"] < depth["max"] < 5  # metres


def test_non_finite_values_are_counted_not_refused(tmp_path, record_with):
    def nan_at_step_3(i):
        return {K.MEASURED_EEF_WRENCH: np.full(6, np.nan) if i == 3 else np.ones(6) * i}

    info = episode_info(record_with(tmp_path / "ep.hdf5", extra=nan_at_step_3))
    wrench = info["keys"][K.MEASURED_EEF_WRENCH]
    assert wrench["non_finite"] == 6
    assert wrench["min"] == 0 and wrench["max"] == 11
    assert "(6 non-finite)" in format_info(info)


def test_summary_over_a_directory_reports_unreadable_episodes(tmp_path, record, record_with):
    record(tmp_path / "a.rmb")
    record_with(tmp_path / "b.hdf5", extra=lambda i: {K.REWARD: 0.0}, num_steps=8)
    (tmp_path / "broken.hdf5").write_bytes(b"not an hdf5 file")
    infos, errors = collect_info([tmp_path], progress=False)
    assert [i["steps"] for i in infos] == [12, 8]
    assert len(errors) == 1 and errors[0][0].name == "broken.hdf5"
    stats = summary(infos, len(errors))
    assert stats["length_mean"] == 10 and stats["length_min"] == 8 and stats["length_max"] == 12
    assert stats["success_once"] == 1 and stats["success_last"] == 1 and stats["unreadable"] == 1
