"""Depth videos of a conversion: lossless at the faster x265 preset, read by LeRobot unmodified."""

from __future__ import annotations

import json

import av
import numpy as np
import torch
from lerobot.configs import DepthEncoderConfig
from lerobot.datasets.depth_utils import dequantize_depth, quantize_depth
from lerobot.datasets.lerobot_dataset import LeRobotDataset

from rmb_lerobot import find_episodes, open_episode
from rmb_lerobot import keys as K
from rmb_lerobot import lerobot_names as N
from rmb_lerobot.converters.write import DEPTH_PRESET, clamp_depth

CAMERAS = ("front", "hand")  # what the demos fixture records


def expected_codes(demos, camera: str) -> np.ndarray:
    """The 12-bit codes LeRobot's quantiser gives the recorded depth, episodes in order."""
    codes = []
    for path in find_episodes(demos):
        with open_episode(path) as episode:
            depth, _ = clamp_depth(np.asarray(episode[K.depth_image_key(camera)][:]))
        codes.extend(quantize_depth(frame, video_backend=None) for frame in depth)
    return np.stack(codes)


def decoded_codes(root, feature: str) -> np.ndarray:
    """Every frame of a depth feature's video files, decoded as stored (gray12le codes)."""
    frames = []
    for video in sorted((root / "videos" / feature).rglob("*.mp4")):
        with av.open(str(video)) as container:
            frames.extend(frame.to_ndarray() for frame in container.decode(video=0))
    return np.stack(frames)


def test_depth_videos_decode_to_exactly_the_quantised_depth(converted_depth, demos):
    for camera in CAMERAS:
        feature = N.depth_image_key(camera)
        expected = expected_codes(demos, camera)
        decoded = decoded_codes(converted_depth, feature)
        assert decoded.dtype == np.uint16 and decoded.shape == expected.shape
        np.testing.assert_array_equal(decoded, expected)
        assert len(np.unique(decoded)) > 10  # real depth, not a constant image


def test_info_records_the_preset_and_lerobot_reads_the_same_depth(converted_depth, demos):
    info = json.loads((converted_depth / "meta" / "info.json").read_text())
    feature = N.depth_image_key("hand")
    assert info["features"][feature]["info"]["video.preset"] == DEPTH_PRESET
    dataset = LeRobotDataset(
        f"local/{converted_depth.name}", root=converted_depth, video_backend="pyav"
    )
    codes = expected_codes(demos, "hand")
    config = DepthEncoderConfig()
    for index in (0, 5, len(dataset) - 1):
        expected_mm = dequantize_depth(
            codes[index][None, None],
            depth_min=config.depth_min,
            depth_max=config.depth_max,
            shift=config.shift,
            use_log=config.use_log,
            output_unit="mm",
            output_tensor=False,
        )
        loaded = dataset[index][feature]
        assert isinstance(loaded, torch.Tensor)
        np.testing.assert_array_equal(loaded.numpy(), np.asarray(expected_mm)[0])
