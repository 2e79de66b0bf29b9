"""to-lerobot --image-features: RGB as LeRobot image features, frames exactly the episodes' own.

What changes against the default (AV1 video): a policy trained on the dataset sees the RMB
episodes' decoded frames exactly instead of their AV1 re-encoding; everything else it is given
(state, action chunks, timestamps, indices) is the same tensor for tensor.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch
from lerobot.datasets.lerobot_dataset import LeRobotDataset

from rmb_lerobot import find_episodes, open_episode
from rmb_lerobot import keys as K
from rmb_lerobot import lerobot_names as N
from rmb_lerobot.cli.convert import main as convert_main
from rmb_lerobot.converters import ConvertOptions, from_lerobot, to_lerobot

from .conftest import CAMERAS

RATE = 125 / 4  # the demos' control rate (Hz)


def _load(root, **kwargs) -> LeRobotDataset:
    return LeRobotDataset(f"local/{root.name}", root=root, video_backend="pyav", **kwargs)


@pytest.fixture(scope="module")
def as_images(demos, tmp_path_factory):
    root = tmp_path_factory.mktemp("images") / "insert_images"
    options = ConvertOptions(extra_keys=False, image_features=True)
    to_lerobot([demos], output=root, options=options, progress=False)
    return root


@pytest.fixture(scope="module")
def as_video(demos, tmp_path_factory):
    root = tmp_path_factory.mktemp("video") / "insert_video"
    to_lerobot([demos], output=root, options=ConvertOptions(extra_keys=False), progress=False)
    return root


def _uint8(frame: torch.Tensor) -> np.ndarray:
    """A loaded (C, H, W) float frame in [0, 1] as the (H, W, C) uint8 image it came from."""
    return np.rint(frame.numpy().transpose(1, 2, 0) * 255).astype(np.uint8)


def test_cameras_are_image_features_with_image_statistics(as_images):
    info = json.loads((as_images / "meta" / "info.json").read_text())
    stats = json.loads((as_images / "meta" / "stats.json").read_text())
    for camera in CAMERAS:
        feature = info["features"][N.image_key(camera)]
        assert feature["dtype"] == "image" and feature["shape"] == [32, 32, 3]
        # LeRobot's per-channel image statistics, scaled to [0, 1] as for videos.
        for name in ("min", "max", "mean", "std"):
            values = np.asarray(stats[N.image_key(camera)][name])
            assert values.shape == (3, 1, 1) and (values >= 0).all() and (values <= 1).all()
    assert not list(as_images.rglob("*.mp4"))  # no video at all without depth


def test_the_policy_sees_the_episodes_own_frames(demos, as_images):
    dataset = _load(as_images)
    first = 0
    for index, path in enumerate(find_episodes(demos)):
        with open_episode(path) as episode:
            frames = {c: episode[K.rgb_image_key(c)][:] for c in CAMERAS}
        steps = len(frames[CAMERAS[0]])
        for i in range(steps):
            item = dataset[first + i]
            assert int(item["episode_index"]) == index and int(item["frame_index"]) == i
            for camera in CAMERAS:
                np.testing.assert_array_equal(_uint8(item[N.image_key(camera)]), frames[camera][i])
        first += steps
    assert first == len(dataset)


def test_everything_but_the_frames_is_what_the_video_form_gives(as_images, as_video):
    # What ACT samples: state and images at t, an action chunk t .. t+7 with its padding mask.
    delta = {N.ACTION_KEY: [i / RATE for i in range(8)]}
    images, video = (
        _load(as_images, delta_timestamps=delta),
        _load(as_video, delta_timestamps=delta),
    )
    assert len(images) == len(video)
    for index in (0, 5, len(images) // 2, len(images) - 1):
        a, b = images[index], video[index]
        assert a.keys() == b.keys()
        for key in a:
            if key in {N.image_key(c) for c in CAMERAS}:
                # Same layout as decoded video frames; only the pixel values' AV1 loss differs.
                assert a[key].shape == b[key].shape and a[key].dtype == b[key].dtype
                assert (a[key] - b[key]).abs().mean() < 0.05, key
            elif isinstance(a[key], torch.Tensor):
                assert torch.equal(a[key], b[key]), (index, key)
            else:
                assert a[key] == b[key], (index, key)


def test_from_lerobot_restores_the_exact_frames(demos, as_images, tmp_path):
    # HDF5 episodes store frames raw, so the round trip through image features is lossless.
    back = from_lerobot(root=as_images, output=tmp_path / "back", fmt="hdf5", progress=False)
    sources = find_episodes(demos)
    assert len(back) == len(sources)
    for source, restored in zip(sources, back, strict=True):
        with open_episode(source) as a, open_episode(restored) as b:
            for camera in CAMERAS:
                key = K.rgb_image_key(camera)
                np.testing.assert_array_equal(b[key][:], a[key][:], key)
            np.testing.assert_array_equal(
                b[K.MEASURED_JOINT_POS][:].astype(np.float32),
                a[K.MEASURED_JOINT_POS][:].astype(np.float32),
            )


def test_depth_stays_video_beside_image_features(demos, tmp_path):
    root = tmp_path / "rgbd"
    options = ConvertOptions(extra_keys=False, image_features=True, depth=True)
    to_lerobot([demos], output=root, options=options, progress=False)
    features = _load(root).meta.features
    assert features[N.image_key("front")]["dtype"] == "image"
    depth = features[N.depth_image_key("front")]
    assert depth["dtype"] == "video" and depth["info"]["is_depth_map"]


def test_sharded_conversion_gives_the_same_rows(demos, as_images, tmp_path):
    root = tmp_path / "sharded"
    options = ConvertOptions(extra_keys=False, image_features=True)
    to_lerobot([demos], output=root, options=options, workers=2, progress=False)
    a, b = _load(as_images), _load(root)
    assert len(a) == len(b)
    for index in (0, len(a) // 2 - 1, len(a) // 2, len(a) - 1):  # both shards' ends
        for key in (N.STATE, N.ACTION_KEY, *(N.image_key(c) for c in CAMERAS)):
            assert torch.equal(a[index][key], b[index][key]), (index, key)


def test_copy_codec_and_image_features_are_refused_together(demos, tmp_path):
    with pytest.raises(ValueError, match=r"--video-codec copy .* --image-features"):
        to_lerobot(
            [demos],
            output=tmp_path / "x",
            options=ConvertOptions(image_features=True),
            video_codec="copy",
            progress=False,
        )
    assert not (tmp_path / "x").exists()


def test_the_command_line_flag(demos, tmp_path, capsys):
    out = tmp_path / "cli"
    convert_main(["to-lerobot", str(demos), f"--output={out}", "--image-features"])
    assert "wrote LeRobotDataset" in capsys.readouterr().out
    assert _load(out).meta.features[N.image_key("hand")]["dtype"] == "image"
