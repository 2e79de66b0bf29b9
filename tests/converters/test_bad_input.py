"""Bad input to to-lerobot: clear errors naming file and key, and nothing at the destination."""

from __future__ import annotations

import json
import re

import h5py
import numpy as np
import pytest
from lerobot.datasets.lerobot_dataset import LeRobotDataset

from rmb_lerobot import EpisodeWriter, RmbFormatError, find_episodes
from rmb_lerobot import keys as K
from rmb_lerobot import lerobot_names as N
from rmb_lerobot.converters import ConvertOptions, to_lerobot
from rmb_lerobot.converters.encoder import ConversionDataset


def _convert(src, dest, **options):
    return to_lerobot(
        [src], output=dest, options=ConvertOptions(**options), video_codec="h264", progress=False
    )


def _assert_nothing_written(dest, hidden_entries):
    assert not dest.exists()
    assert hidden_entries(dest.parent) == []


def test_missing_state_key_names_the_option_file_and_key(demos, tmp_path, hidden_entries):
    dest = tmp_path / "ds"
    with pytest.raises(RmbFormatError) as err:
        _convert(demos, dest, state_keys=(K.MEASURED_JOINT_POS, K.MEASURED_JOINT_TORQUE))
    message = str(err.value)
    assert "--state-keys" in message and "measured_joint_torque" in message
    assert "MujocoUR5eInsert_world0_000.rmb" in message
    _assert_nothing_written(dest, hidden_entries)


def test_missing_camera_is_named(demos, tmp_path):
    with pytest.raises(RmbFormatError, match="--camera-names names 'left'"):
        _convert(demos, tmp_path / "ds", camera_names=("front", "left"))


def _retag(path, **attrs):
    with h5py.File(path / K.COMPACT_MAIN_FILE, "r+") as h5:
        for name, value in attrs.items():
            h5.attrs[name] = value


def test_mixed_envs_are_refused(demo_copy, tmp_path, hidden_entries):
    second = find_episodes(demo_copy)[1]
    _retag(second, env="MujocoUR5eDoorEnv")
    dest = tmp_path / "ds"
    with pytest.raises(RmbFormatError) as err:
        _convert(demo_copy, dest)
    message = str(err.value)
    assert "mixed envs" in message and "MujocoUR5eDoorEnv" in message and second.name in message
    _assert_nothing_written(dest, hidden_entries)


def test_mixed_frame_rates_are_refused(demo_copy, tmp_path):
    second = find_episodes(demo_copy)[1]
    with h5py.File(second / K.COMPACT_MAIN_FILE, "r+") as h5:
        h5[K.TIME][...] = h5[K.TIME][...] * 2  # 15.625 Hz
    with pytest.raises(RmbFormatError) as err:
        _convert(demo_copy, tmp_path / "ds")
    message = str(err.value)
    assert "mixed frame rates" in message and "31.25 Hz" in message and "15.625 Hz" in message
    assert second.name in message and "'time'" in message


def test_truncated_hdf5_is_a_corrupt_episode(demo_copy, tmp_path, hidden_entries):
    main = find_episodes(demo_copy)[1] / K.COMPACT_MAIN_FILE
    main.write_bytes(main.read_bytes()[:2000])
    dest = tmp_path / "ds"
    with pytest.raises(RmbFormatError, match="corrupt") as err:
        _convert(demo_copy, dest)
    assert str(main) in str(err.value)
    _assert_nothing_written(dest, hidden_entries)


def test_corrupt_video_fails_naming_the_file(demo_copy, tmp_path, hidden_entries):
    video = find_episodes(demo_copy)[1] / "hand_rgb_image.rmb.mp4"
    video.write_bytes(b"\x00" * 64 + video.read_bytes()[64:200])
    dest = tmp_path / "ds"
    with pytest.raises(RmbFormatError) as err:
        _convert(demo_copy, dest)
    assert "hand_rgb_image" in str(err.value)
    _assert_nothing_written(dest, hidden_entries)


def test_existing_destination_needs_overwrite(demos, tmp_path):
    dest = tmp_path / "ds"
    dest.mkdir()
    (dest / "keep.txt").write_text("mine")
    with pytest.raises(FileExistsError, match="--overwrite"):
        _convert(demos, dest)
    assert (dest / "keep.txt").read_text() == "mine"
    to_lerobot(
        [demos],
        output=dest,
        options=ConvertOptions(camera_names=("hand",)),
        video_codec="h264",
        overwrite=True,
        progress=False,
    )
    assert not (dest / "keep.txt").exists() and (dest / "meta" / "info.json").is_file()


@pytest.mark.parametrize("exception", [RuntimeError("disk full"), KeyboardInterrupt()])
def test_a_failure_midway_leaves_nothing(demos, tmp_path, monkeypatch, hidden_entries, exception):
    original = ConversionDataset.save_episode
    calls = {"n": 0}

    def fail_on_second(self, *args, **kwargs):
        calls["n"] += 1
        if calls["n"] == 2:
            raise exception
        return original(self, *args, **kwargs)

    monkeypatch.setattr(ConversionDataset, "save_episode", fail_on_second)
    dest = tmp_path / "ds"
    with pytest.raises(type(exception)) as err:
        _convert(demos, dest)
    assert calls["n"] == 2
    assert "MujocoUR5eInsert_world1_001.rmb" in " ".join(getattr(err.value, "__notes__", []))
    _assert_nothing_written(dest, hidden_entries)


def test_episode_without_time_needs_fps(tmp_path, steps, attrs):
    path = tmp_path / "src" / "a.hdf5"
    with EpisodeWriter(path, attrs) as writer:
        for step in steps:
            writer.append(step)
    with h5py.File(path, "r+") as h5:
        del h5[K.TIME]
    with pytest.raises(RmbFormatError, match="pass --fps"):
        _convert(path.parent, tmp_path / "ds")
    root = tmp_path / "ds"
    _convert(path.parent, root, fps="125/4", camera_names=("front",))
    assert (root / "meta" / "info.json").is_file()
    assert json.loads((root / "meta" / "info.json").read_text())["fps"] == 31.25


def _set(path, key, index, value):
    """Write ``value`` at ``index`` of an episode's HDF5 dataset ``key`` (as float64)."""
    main = path / K.COMPACT_MAIN_FILE if path.suffix == ".rmb" else path
    with h5py.File(main, "r+") as h5:
        data = h5[key][()].astype(np.float64)
        data[index] = value
        del h5[key]
        h5.create_dataset(key, data=data)


def test_nan_in_a_lowdim_key_is_refused_naming_file_key_and_step(
    demo_copy, tmp_path, hidden_entries
):
    second = find_episodes(demo_copy)[1]
    _set(second, K.MEASURED_JOINT_POS, (5, 2), np.nan)
    dest = tmp_path / "ds"
    with pytest.raises(RmbFormatError) as err:
        _convert(demo_copy, dest)
    message = str(err.value)
    assert second.name in message and K.MEASURED_JOINT_POS in message
    assert re.search(r"\bnan\b", message) and re.search(r"\b5\b", message), message
    _assert_nothing_written(dest, hidden_entries)


def test_allow_non_finite_keeps_nan_and_computes_stats_over_finite_values(demo_copy, tmp_path):
    first = find_episodes(demo_copy)[0]
    _set(first, K.MEASURED_JOINT_POS, (5, 2), np.nan)
    _set(first, K.MEASURED_JOINT_POS, (6, 3), np.inf)
    dest = tmp_path / "ds"
    _convert(demo_copy, dest, camera_names=("hand",), allow_non_finite=True)
    state = np.stack(
        LeRobotDataset("local/ds", root=dest).hf_dataset.with_format("numpy")[:][N.STATE]
    )
    assert np.isnan(state[5, 2]) and np.isposinf(state[6, 3])
    stats = json.loads((dest / "meta" / "stats.json").read_text())[N.STATE]
    masked = np.ma.masked_invalid(state.astype(np.float64))
    np.testing.assert_allclose(stats["min"], masked.min(axis=0), rtol=1e-6)
    np.testing.assert_allclose(stats["max"], masked.max(axis=0), rtol=1e-6)
    np.testing.assert_allclose(stats["mean"], masked.mean(axis=0), rtol=1e-5)
    assert stats["count"] == [len(state)]


def test_a_value_beyond_float32_is_refused_at_the_cast(demo_copy, tmp_path, hidden_entries):
    second = find_episodes(demo_copy)[1]
    _set(second, K.COMMAND_JOINT_POS, (7, 1), 1e39)
    dest = tmp_path / "ds"
    with pytest.raises(RmbFormatError, match="beyond float32's range") as err:
        _convert(demo_copy, dest)
    message = str(err.value)
    assert second.name in message and K.COMMAND_JOINT_POS in message
    assert "1e+39 at step 7, component (1,)" in message
    _assert_nothing_written(dest, hidden_entries)


def _retime(path, change):
    with h5py.File(path / K.COMPACT_MAIN_FILE, "r+") as h5:
        time = h5[K.TIME][()]
        del h5[K.TIME]
        h5.create_dataset(K.TIME, data=change(time))


def _gap(time):
    time = time.copy()
    time[10:] += 0.3
    return time


def test_a_gap_in_time_is_refused_unless_fps_is_given(demo_copy, tmp_path, caplog):
    second = find_episodes(demo_copy)[1]
    _retime(second, _gap)
    with pytest.raises(RmbFormatError, match=r"'time' jumps by 0\.332 s at step 10") as err:
        _convert(demo_copy, tmp_path / "ds")
    assert second.name in str(err.value) and "pass --fps RATE" in str(err.value)
    dest = tmp_path / "ds"
    _convert(demo_copy, dest, fps="125/4", camera_names=("hand",))  # the user asserts the rate
    assert json.loads((dest / "meta" / "info.json").read_text())["fps"] == 31.25
    warned = [r.getMessage() for r in caplog.records if "jumps by" in r.getMessage()]
    assert warned and second.name in warned[0] and "using --fps 125/4" in warned[0]


def test_time_in_milliseconds_is_refused(demo_copy, tmp_path):
    first = find_episodes(demo_copy)[0]
    _retime(first, lambda time: time * 1000)
    with pytest.raises(RmbFormatError, match=r"0\.03125 Hz .* in milliseconds") as err:
        _convert(demo_copy, tmp_path / "ds")
    assert first.name in str(err.value)


@pytest.mark.parametrize(
    ("attr", "value", "expected"),
    [
        ("hand_depth_image_fovy", "wide", "field of view"),
        ("hand_depth_image_fovy", np.nan, "field of view"),
        ("front_depth_image_fovy", 180.0, "field of view"),
        ("world_idx", "3", "an integer"),
        ("world_idx", 1.5, "an integer"),
        ("camera_names", 7, "list of"),
        ("task_desc", 42, "string"),
        ("recorded_by", np.array([1.0, np.nan]), "a finite number"),
    ],
)
def test_bad_attributes_are_refused_naming_file_and_attribute(
    demo_copy, tmp_path, hidden_entries, attr, value, expected
):
    second = find_episodes(demo_copy)[1]
    _retag(second, **{attr: value})
    dest = tmp_path / "ds"
    with pytest.raises(RmbFormatError, match=expected) as err:
        _convert(demo_copy, dest)
    message = str(err.value)
    assert repr(attr) in message and str(second / K.COMPACT_MAIN_FILE) in message
    _assert_nothing_written(dest, hidden_entries)
