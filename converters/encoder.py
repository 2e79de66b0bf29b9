"""LeRobot's streaming video encoder, made fit for converting recorded data.

Frames go straight from the decoded RMB video to LeRobot's per-camera encoder threads
(:class:`~lerobot.datasets.video_utils.StreamingVideoEncoder`): no temporary PNG/TIFF files as
in ``add_frame``'s default path. Changes over LeRobot's recorder settings:

- the frame rate is an exact fraction (31.25 Hz -> 125/4), which PyAV needs and LeRobot's own
  writer cannot produce from a non-integer ``fps`` (see :mod:`.rate`);
- a full queue blocks instead of dropping the frame: a recorder must keep up with a camera, a
  converter must keep every frame;
- cameras marked for copying (``--video-codec copy``, :mod:`.copy`) are not encoded at all:
  their frames only feed LeRobot's image statistics and the episode's video is remuxed from
  the RMB file.
"""

from __future__ import annotations

import contextlib
import queue
import shutil
import tempfile
from collections.abc import Mapping
from fractions import Fraction
from pathlib import Path
from unittest import mock

import datasets
import numpy as np
from datasets.table import embed_table_storage
from lerobot.configs import DepthEncoderConfig, RGBEncoderConfig
from lerobot.datasets import dataset_writer
from lerobot.datasets.compute_stats import RunningQuantileStats, auto_downsample_height_width
from lerobot.datasets.lerobot_dataset import LeRobotDataset
from lerobot.datasets.video_utils import StreamingVideoEncoder

from rmb_lerobot.converters.copy import remux
from rmb_lerobot.converters.rate import exact_rate
from rmb_lerobot.converters.stats import finite_episode_stats

# Seconds between checks that an encoder thread is still alive while waiting for queue space.
_POLL_S = 1.0


class _CopiedVideo:
    """A camera whose packets are copied: image statistics as LeRobot's encoder thread keeps."""

    def __init__(self, source: Path, temp_dir: Path):
        self.source = source
        self.path = Path(tempfile.mkdtemp(dir=temp_dir)) / "copied.mp4"
        self.stats = RunningQuantileStats()
        self.frames = 0

    def add(self, image: np.ndarray) -> None:
        chw = image.transpose(2, 0, 1)
        small = auto_downsample_height_width(chw)
        self.stats.update(small.transpose(1, 2, 0).reshape(-1, small.shape[0]))
        self.frames += 1

    def finish(self, rate: Fraction) -> tuple[Path, dict | None]:
        remux(self.source, self.path, rate, self.frames)
        return self.path, self.stats.get_statistics() if self.frames >= 2 else None

    def discard(self) -> None:
        shutil.rmtree(self.path.parent, ignore_errors=True)


class ConversionEncoder(StreamingVideoEncoder):
    """:class:`StreamingVideoEncoder` at an exact rate that never drops a frame and can copy."""

    def __init__(self, fps: Fraction, **kwargs):
        super().__init__(fps=Fraction(fps), **kwargs)
        self._copy_sources: dict[str, Path] = {}
        self._copied: dict[str, _CopiedVideo] = {}

    def copy_from(self, sources: Mapping[str, Path]) -> None:
        """Copy these video keys from these files in the next episode instead of encoding."""
        self._copy_sources = {key: Path(path) for key, path in sources.items()}

    def start_episode(
        self, video_keys: list[str], temp_dir: Path, depth_video_keys: list[str] | None = None
    ) -> None:
        self._discard_copies()
        encoded = [key for key in video_keys if key not in self._copy_sources]
        super().start_episode(encoded, temp_dir, depth_video_keys)
        for key in video_keys:
            if key in self._copy_sources:
                self._copied[key] = _CopiedVideo(self._copy_sources[key], Path(temp_dir))

    def feed_frame(self, video_key: str, image: np.ndarray) -> None:
        if not self._episode_active:
            raise RuntimeError("No active episode. Call start_episode() first.")
        if video_key in self._copied:
            self._copied[video_key].add(image)
            return
        frames, thread = self._frame_queues[video_key], self._threads[video_key]
        while True:
            if not thread.is_alive():
                super().feed_frame(video_key, image)  # raises with the thread's error
            try:
                frames.put(image, timeout=_POLL_S)  # decoded frames are never reused: no copy
                return
            except queue.Full:
                continue

    def finish_episode(self) -> dict[str, tuple[Path, dict | None]]:
        copied, self._copied = self._copied, {}
        try:
            results = super().finish_episode()
            results.update({key: video.finish(self.fps) for key, video in copied.items()})
        except BaseException:
            for video in copied.values():
                video.discard()
            raise
        self._copy_sources = {}
        return results

    def cancel_episode(self) -> None:
        self._discard_copies()
        super().cancel_episode()

    def _discard_copies(self) -> None:
        for video in self._copied.values():
            with contextlib.suppress(Exception):
                video.discard()
        self._copied = {}


def _embed_images_batched(dataset: datasets.Dataset) -> datasets.Dataset:
    """LeRobot's ``embed_images``, on batches of rows instead of one row at a time."""
    format = dataset.format
    dataset = dataset.with_format("arrow").map(embed_table_storage, batched=True)
    return dataset.with_format(**format)


class ConversionDataset(LeRobotDataset):
    """A ``LeRobotDataset`` whose streaming encoder is :class:`ConversionEncoder`.

    Only writing differs; the files are plain LeRobotDataset v3, read with ``LeRobotDataset``.
    ``save_episode`` computes statistics that tolerate NaN/inf (:mod:`.stats`, only reachable
    with ``--allow-non-finite``) and embeds image bytes in batches: LeRobot 0.6.1 maps over the
    episode row by row (``datasets.map(batched=False)``), ~10 ms per frame with RMB's ~25 features
    even when no feature holds images, which made it the largest cost after video encoding.
    """

    def save_episode(self, episode_data: dict | None = None, parallel_encoding: bool = True):
        with (
            mock.patch.object(dataset_writer, "embed_images", _embed_images_batched),
            mock.patch.object(dataset_writer, "compute_episode_stats", finite_episode_stats),
        ):
            super().save_episode(episode_data, parallel_encoding)

    @staticmethod
    def _build_streaming_encoder(
        fps: float,
        rgb_encoder: RGBEncoderConfig | None,
        depth_encoder: DepthEncoderConfig | None,
        encoder_queue_maxsize: int,
        encoder_threads: int | None,
    ) -> StreamingVideoEncoder:
        return ConversionEncoder(
            exact_rate(fps),
            rgb_encoder=rgb_encoder,
            depth_encoder=depth_encoder,
            queue_maxsize=encoder_queue_maxsize,
            encoder_threads=encoder_threads,
        )

    @property
    def video_encoder(self) -> ConversionEncoder:
        """The encoder built above (LeRobot keeps it in a private attribute of its writer)."""
        return self.writer._streaming_encoder
