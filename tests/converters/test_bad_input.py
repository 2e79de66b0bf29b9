"""Bad input to to-lerobot: clear errors naming file and key, and nothing at the destination."""

from __future__ import annotations

import json

import h5py
import pytest
from rmb_lerobot.converters import ConvertOptions, to_lerobot
from rmb_lerobot.converters.encoder import ConversionDataset

from rmb_lerobot import EpisodeWriter, RmbFormatError, find_episodes
from rmb_lerobot import keys as K


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
