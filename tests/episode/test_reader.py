"""open_episode: lazy random access, both variants, compatibility with the original RMB."""

import h5py
import numpy as np
import pytest

from rmb_lerobot import MissingKeyError, RmbFormatError, find_episodes, open_episode


@pytest.mark.parametrize("name", ["demo.rmb", "demo.hdf5"])
def test_round_trip(tmp_path, record, steps, psnr, name):
    with open_episode(record(tmp_path / name)) as ep:
        assert len(ep) == len(steps)
        assert ep.fps == pytest.approx(31.25)
        assert ep.camera_names == ["front", "hand"]
        assert ep.fovy("front") == 45.0
        assert ep.attrs["task_desc"].startswith("Reach")
        for key in ("time", "measured_joint_pos", "command_joint_pos", "measured_eef_wrench"):
            np.testing.assert_array_equal(ep[key][:], np.stack([s[key] for s in steps]))
        rgb = ep["front_rgb_image"][:]
        depth = ep["hand_depth_image"][:]
        assert rgb.dtype == np.uint8 and rgb.shape == (12, 48, 64, 3)
        assert depth.dtype == np.float32 and depth.shape == (12, 48, 64)
        truth_rgb = np.stack([s["front_rgb_image"] for s in steps])
        truth_depth = np.stack([s["hand_depth_image"] for s in steps])
        assert psnr(rgb, truth_rgb) > 30
        # Compact: depth rounded to whole millimetres (at most 0.5 mm off); single file: exact.
        assert np.abs(depth - truth_depth).max() <= 0.0005 + 1e-6


@pytest.mark.parametrize("name", ["demo.rmb", "demo.hdf5"])
def test_random_access_matches_sequential_reading(tmp_path, record, name):
    with open_episode(record(tmp_path / name)) as ep:
        for key in ("front_rgb_image", "front_depth_image", "measured_joint_pos"):
            series = ep[key]
            everything = series[:]
            np.testing.assert_array_equal(series[7], everything[7])
            np.testing.assert_array_equal(series[-1], everything[-1])
            np.testing.assert_array_equal(series[3:9:2], everything[3:9:2])
            np.testing.assert_array_equal(series[[9, 2, 2, 5]], everything[[9, 2, 2, 5]])


@pytest.mark.parametrize("name", ["demo.rmb", "demo.hdf5"])
def test_resize_on_read(tmp_path, record, name):
    with open_episode(record(tmp_path / name), image_size=(32, 24)) as ep:
        assert ep["front_rgb_image"][0].shape == (24, 32, 3)
        assert ep["front_rgb_image"][0:3].shape == (3, 24, 32, 3)
        assert ep["hand_depth_image"][2:4].shape == (2, 24, 32)
        assert ep["hand_depth_image"][2].dtype == np.float32


def test_cache_loads_each_key_once_into_memory(tmp_path, record):
    with open_episode(record(tmp_path / "demo.rmb"), cache=True) as ep:
        first = ep["front_rgb_image"]
        assert isinstance(first, np.ndarray) and first.shape == (12, 48, 64, 3)
        assert ep["front_rgb_image"] is first


def test_keys_list_datasets_and_videos(tmp_path, record):
    with open_episode(record(tmp_path / "demo.rmb")) as ep:
        keys = ep.keys()
        assert {"front_rgb_image", "hand_depth_image", "measured_eef_pose_rel"} <= set(keys)
        assert "front_rgb_image" in ep and "back_rgb_image" not in ep


@pytest.mark.parametrize("name", ["original.rmb", "original.hdf5"])
def test_episodes_written_by_the_original_rmb_read_correctly(
    tmp_path, steps, attrs, write_like_original, psnr, name
):
    meta = {**attrs, "version": "1.0.0", "rgb_tactile_names": [], "camera_names": ["front", "hand"]}
    path = write_like_original(tmp_path / name, steps, meta)
    with open_episode(path) as ep:
        assert len(ep) == 12 and ep.attrs["rgb_tactile_names"] == []
        assert ep.attrs["camera_names"] == ["front", "hand"]
        assert ep.camera_names == ["front", "hand"]
        joints = np.stack([s["measured_joint_pos"] for s in steps])
        np.testing.assert_array_equal(ep["measured_joint_pos"][:], joints)
        truth = np.stack([s["front_depth_image"] for s in steps])
        if ep.format.short_name == "rmb":
            # The original truncates to millimetres: we read exactly what it stored.
            stored = (truth * 1e3).astype(np.uint16) / np.float32(1e3)
            np.testing.assert_array_equal(ep["front_depth_image"][:], stored)
            assert psnr(ep["hand_rgb_image"][5], steps[5]["hand_rgb_image"]) > 30
        else:
            np.testing.assert_array_equal(ep["front_depth_image"][:], truth)
            np.testing.assert_array_equal(ep["hand_rgb_image"][5], steps[5]["hand_rgb_image"])


def test_episodes_we_write_read_with_the_original_loader(
    tmp_path, record, steps, read_like_original, psnr
):
    ours = record(tmp_path / "demo.rmb")
    data, attrs = read_like_original(ours)
    assert attrs["format"] == "RmbData-Compact"
    assert [str(c) for c in attrs["camera_names"]] == ["front", "hand"]
    assert data["front_rgb_image"].shape == (12, 48, 64, 3)
    assert psnr(data["front_rgb_image"], np.stack([s["front_rgb_image"] for s in steps])) > 30
    truth = np.stack([s["hand_depth_image"] for s in steps])
    assert np.abs(data["hand_depth_image"] - truth).max() <= 0.0005 + 1e-6
    np.testing.assert_array_equal(
        data["command_joint_pos"], np.stack([s["command_joint_pos"] for s in steps])
    )


# ---------------------------------------------------------------- bad input
def test_wrong_extension_is_named(tmp_path):
    with pytest.raises(RmbFormatError, match=r"invalid episode extension '\.zip'") as info:
        open_episode(tmp_path / "demo.zip")
    assert info.value.path == tmp_path / "demo.zip"


def test_inner_file_of_a_compact_episode_is_refused_with_a_hint(tmp_path, record):
    path = record(tmp_path / "demo.rmb")
    with pytest.raises(RmbFormatError, match=r"open its \.rmb directory"):
        open_episode(path / "main.rmb.hdf5")


def test_missing_episode(tmp_path):
    with pytest.raises(RmbFormatError, match="episode not found"):
        open_episode(tmp_path / "nothing.rmb")


def test_truncated_hdf5_is_reported_with_its_file(tmp_path, record):
    path = record(tmp_path / "demo.hdf5")
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 3])
    with (
        pytest.raises(RmbFormatError, match="truncated or corrupt") as info,
        open_episode(path) as ep,
    ):
        ep["front_rgb_image"][:]
    assert info.value.path == path


def test_corrupt_video_is_reported_with_its_file(tmp_path, record):
    path = record(tmp_path / "demo.rmb")
    video = path / "front_rgb_image.rmb.mp4"
    video.write_bytes(video.read_bytes()[:200])
    with open_episode(path) as ep, pytest.raises(RmbFormatError) as info:
        ep["front_rgb_image"][5]
    assert "front_rgb_image.rmb.mp4" in str(info.value)


def test_missing_key_is_a_key_error_naming_the_key(tmp_path, record):
    with open_episode(record(tmp_path / "demo.rmb")) as ep:
        with pytest.raises(MissingKeyError, match="key 'left_rgb_image'"):
            ep["left_rgb_image"]
        with pytest.raises(KeyError):
            ep["measured_mobile_omni_vel"]
        with pytest.raises(MissingKeyError, match="left_depth_image_fovy"):
            ep.fovy("left")


def test_length_mismatch_between_keys_is_reported(tmp_path, record):
    path = record(tmp_path / "demo.rmb")
    with h5py.File(path / "main.rmb.hdf5", "a") as h5:
        del h5["reward"]
        h5.create_dataset("reward", data=np.zeros(5))
    with open_episode(path) as ep:
        with pytest.raises(RmbFormatError, match="has 5 steps but the episode has 12") as info:
            ep["reward"]
        assert info.value.key == "reward"
        with pytest.raises(RmbFormatError, match="has 5 steps"):
            ep.validate()


def test_length_mismatch_between_keys_and_video_frames_is_reported(tmp_path, record, steps, attrs):
    short = record(tmp_path / "short.rmb")
    long = tmp_path / "long.rmb"
    from rmb_lerobot import EpisodeWriter

    with EpisodeWriter(long, attrs) as writer:
        for step in steps + steps[:3]:
            writer.append(step)
    (short / "front_rgb_image.rmb.mp4").write_bytes((long / "front_rgb_image.rmb.mp4").read_bytes())
    with (
        open_episode(short) as ep,
        pytest.raises(RmbFormatError, match="video has 15 frames but the episode has 12"),
    ):
        ep["front_rgb_image"]


def test_find_episodes_scans_like_rmb(tmp_path, record):
    record(tmp_path / "b.rmb")
    record(tmp_path / "a.hdf5")
    (tmp_path / "notes.txt").write_text("x")
    (tmp_path / "stray.rmb.hdf5").write_bytes(b"")
    assert [p.name for p in find_episodes(tmp_path)] == ["a.hdf5", "b.rmb"]
    with pytest.raises(RmbFormatError, match="not an episode"):
        find_episodes(tmp_path / "notes.txt")
