"""``rmb-videoio``: the original RMB depth video (the ``videoio`` uint16 scheme), bit for bit.

Depth in uint16 mm is split into ``hi = d >> 8`` and ``lo = d & 255``; where ``hi`` is odd,
``lo`` is stored as ``255 - lo`` so that neighbouring depths stay neighbouring byte values
("folding"). The frame is yuv444p with Y = folded lo, U = 0, V = hi, encoded losslessly by
libx264 (profile high444, CRF 0). Decoding reverses this exactly.
"""

from __future__ import annotations

from pathlib import Path

import av
import numpy as np

from rmb_lerobot.codecs.depth_base import DepthCodec, DepthReader, DepthWriter, as_depth_mm
from rmb_lerobot.codecs.indexing import FrameIndex, resolve_index
from rmb_lerobot.codecs.video import DEPTH_VIDEO_PIX_FMT as PIX_FMT
from rmb_lerobot.codecs.video import VideoFileWriter, VideoFrameReader
from rmb_lerobot.errors import RmbFormatError

# Keyframe interval of the files we write. A random read decodes ~GOP/2 frames on average. The
# original used x264's default 250 (a random read of a 300-frame episode decodes ~125 frames,
# and the original decodes the whole file anyway). Measured on synthetic 640x480 depth
# (benchmarks/depth_codecs.py): noisy sensor-like depth is the same size at 30 as at 250
# (lossless coding of noise dominates), clean rendered depth ~1.5x larger (still tiny); a
# random read then decodes ~15 frames instead of ~125. Files with any GOP are read.
VIDEOIO_GOP = 30


def fold_depth(depth_mm: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """uint16 mm -> (Y = folded low byte, V = high byte), both uint8."""
    hi = (depth_mm >> 8).astype(np.uint8)
    lo = (depth_mm & 0xFF).astype(np.uint8)
    return np.where(hi & 1, 255 - lo, lo).astype(np.uint8), hi


def unfold_depth(y: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Inverse of :func:`fold_depth`."""
    lo = np.where(v & 1, 255 - y, y).astype(np.uint16)
    return (v.astype(np.uint16) << 8) | lo


class VideoioDepthWriter(DepthWriter):
    def __init__(self, path: str | Path, width: int, height: int, *, preset: str, gop: int | None):
        options = {"crf": "0", "preset": preset, "profile": "high444"}
        if gop is not None:
            options["g"] = str(gop)
        self._video = VideoFileWriter(
            path, width, height, codec="libx264", pix_fmt=PIX_FMT, options=options
        )
        self.path = self._video.path
        self._zeros = np.zeros((self._video.height, self._video.width), dtype=np.uint8)

    def write(self, frame: np.ndarray) -> None:
        shape = (self._video.height, self._video.width)
        y, v = fold_depth(as_depth_mm(frame, shape, self.path, len(self._video)))
        planes = np.stack([y, self._zeros, v])
        self._video.encode(av.VideoFrame.from_ndarray(planes, format=PIX_FMT))

    def close(self) -> None:
        self._video.close()


class VideoioDepthReader(DepthReader):
    """uint16 mm frames of an RMB depth video.

    Besides what :class:`VideoFrameReader` detects, every frame is checked against the
    scheme: the stream must be yuv444p and the U plane all zeros. Damage that desynchronises
    the lossless decoder almost always writes non-zero U values, where the V (high byte)
    plane would otherwise decode to depths metres off.
    """

    def __init__(self, path: str | Path):
        self._video = VideoFrameReader(path)
        self.path = self._video.path
        if self._video.pix_fmt != PIX_FMT:
            self._video.close()
            raise RmbFormatError(
                f"depth video stream is {self._video.pix_fmt}; expected {PIX_FMT} (RMB videoio "
                "depth: Y = folded low byte, U = 0, V = high byte)",
                path=self.path,
            )

    def __len__(self) -> int:
        return len(self._video)

    @property
    def shape(self) -> tuple[int, int, int]:
        return (len(self), self._video.height, self._video.width)

    def __getitem__(self, index: FrameIndex) -> np.ndarray:
        positions, single = resolve_index(index, len(self))
        frames = self._video.frames(positions)
        if single:
            return self._to_mm(positions[0], frames[0])
        if not frames:
            return np.empty((0, *self.shape[1:]), dtype=np.uint16)
        return np.stack([self._to_mm(i, f) for i, f in zip(positions, frames, strict=True)])

    def _to_mm(self, i: int, frame: av.VideoFrame) -> np.ndarray:
        planes = frame.to_ndarray(format=PIX_FMT)
        if planes[1].any():
            raise RmbFormatError(
                f"depth video frame {i} is corrupt: its U plane holds non-zero values; "
                "expected U = 0 everywhere (RMB videoio depth)",
                path=self.path,
            )
        return unfold_depth(planes[0], planes[2])

    def close(self) -> None:
        self._video.close()


class VideoioDepthCodec(DepthCodec):
    """The original RMB depth video; ``gop=None`` leaves x264's default (250) like the original."""

    file_suffix = ".rmb.mp4"

    def __init__(
        self, name: str = "rmb-videoio", *, preset: str = "slow", gop: int | None = VIDEOIO_GOP
    ):
        self.name = name
        self.preset = preset
        self.gop = gop

    def writer(self, path: str | Path, width: int, height: int) -> VideoioDepthWriter:
        return VideoioDepthWriter(path, width, height, preset=self.preset, gop=self.gop)

    def reader(self, path: str | Path) -> VideoioDepthReader:
        return VideoioDepthReader(path)
