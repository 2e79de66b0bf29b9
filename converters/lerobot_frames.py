"""Frames of one episode of a LeRobotDataset, decoded with LeRobot's own video code.

``LeRobotDataset[i]`` decodes one frame per call (reopening and seeking the file); converting
a whole episode instead asks LeRobot's decoder for a chunk of timestamps at a time, which seeks
once and decodes forward. Depth goes through LeRobot's ``dequantize_depth`` with the encoder
settings stored in the feature's ``info``, to uint16 millimetres.
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
from lerobot.configs import DepthEncoderConfig
from lerobot.datasets.depth_utils import dequantize_depth
from lerobot.datasets.video_utils import decode_video_frames

# Timestamps per decoder call (one seek each).
CHUNK = 32


def _uint8(array: np.ndarray) -> np.ndarray:
    if array.dtype == np.uint8:
        return array
    return np.clip(np.rint(array * 255.0), 0, 255).astype(np.uint8)  # float images in [0, 1]


def iter_video_frames(
    dataset, episode_index: int, key: str, timestamps: np.ndarray
) -> Iterator[np.ndarray]:
    """Yield chunks of the frames of ``key`` at ``timestamps`` (the episode's ``timestamp``
    column): RGB uint8 ``(n, H, W, 3)`` or depth uint16 millimetres ``(n, H, W)``."""
    meta = dataset.meta
    start = meta.episodes[episode_index][f"videos/{key}/from_timestamp"]
    path = dataset.root / meta.get_video_file_path(episode_index, key)
    is_depth = key in meta.depth_keys
    depth_config = (
        DepthEncoderConfig.from_video_info(meta.features[key].get("info")) if is_depth else None
    )
    for first in range(0, len(timestamps), CHUNK):
        chunk = [start + float(t) for t in timestamps[first : first + CHUNK]]
        frames = decode_video_frames(
            path, chunk, dataset.tolerance_s, "pyav", return_uint8=True, is_depth=is_depth
        )
        if depth_config is None:
            yield np.moveaxis(_uint8(np.asarray(frames)), 1, -1)  # (n, C, H, W) -> (n, H, W, C)
            continue
        depth_mm = dequantize_depth(
            frames,
            depth_min=depth_config.depth_min,
            depth_max=depth_config.depth_max,
            shift=depth_config.shift,
            use_log=depth_config.use_log,
            output_unit="mm",
            output_tensor=False,
        )
        yield np.asarray(depth_mm).reshape(len(chunk), *depth_mm.shape[-2:])


def image_column_frames(images) -> np.ndarray:
    """RGB uint8 ``(n, H, W, 3)`` of a feature stored as images (not video) in parquet rows."""
    return _uint8(np.stack([np.asarray(image) for image in images]))
