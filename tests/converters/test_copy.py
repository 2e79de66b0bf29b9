"""--video-codec copy: the recorded H.264 packets end up in the dataset bit for bit."""

from __future__ import annotations

import shutil

import numpy as np
import pytest
from lerobot.datasets.lerobot_dataset import LeRobotDataset

from rmb_lerobot import RmbFormatError, find_episodes, open_episode, switch_format
from rmb_lerobot import lerobot_names as N
from rmb_lerobot.converters import ConvertOptions, to_lerobot


def _copy(sources, root, **options):
    return to_lerobot(
        sources,
        output=root,
        options=ConvertOptions(**options),
        video_codec="copy",
        progress=False,
    )


def test_copied_frames_are_the_recorded_frames(demo_copy, tmp_path):
    # A third episode: LeRobot appends each episode to one file, so time offsets must add up.
    first = find_episodes(demo_copy)[0]
    shutil.copytree(first, demo_copy / "z_third.rmb")
    root = tmp_path / "copied"
    _copy([demo_copy], root, depth=True)
    dataset = LeRobotDataset("local/copied", root=root, video_backend="pyav")
    info = dataset.meta.features[N.image_key("front")]["info"]
    assert info["video.codec"] == "h264" and info["video.g"] == 10 and info["video.crf"] is None
    assert dataset.meta.features[N.depth_image_key("front")]["info"]["video.codec"] == "hevc"
    for index, path in ((1, find_episodes(demo_copy)[1]), (2, first)):
        start = dataset.meta.episodes[index]["dataset_from_index"]
        with open_episode(path) as ep:
            for i in (0, 9, 10, len(ep) - 1):  # around a keyframe and at the end
                item = dataset[start + i]
                for camera in ("front", "hand"):
                    frame = item[N.image_key(camera)].permute(1, 2, 0).numpy() * 255
                    np.testing.assert_array_equal(np.rint(frame), ep[f"{camera}_rgb_image"][i])
    stats = dataset.meta.stats[N.image_key("hand")]
    assert np.asarray(stats["mean"]).shape == (3, 1, 1) and np.asarray(stats["mean"]).min() > 0


def test_copy_refuses_what_it_cannot_copy(demos, tmp_path, record, hidden_entries):
    with pytest.raises(RmbFormatError, match="cannot --skip"):
        _copy([demos], tmp_path / "a", skip=2)
    single = tmp_path / "single"
    switch_format(find_episodes(demos)[0], single / "a.hdf5")
    with pytest.raises(RmbFormatError, match=r"compact \.rmb"):
        _copy([single], tmp_path / "b")
    mixed = tmp_path / "mixed"
    record(mixed / "a.rmb")
    record(mixed / "b.rmb", rgb_preset="ultrafast")  # other x264 settings: other SPS/PPS
    with pytest.raises(RmbFormatError, match="encoder settings differ") as err:
        _copy([mixed], tmp_path / "c", camera_names=("front",))
    assert "b.rmb" in str(err.value) and "front_rgb_image" in str(err.value)
    assert hidden_entries(tmp_path) == [] and not (tmp_path / "c").exists()
