"""Random-access video on PyAV, shared by RGB streams and depth-in-video codecs.

Reading: :class:`VideoFrameReader` demuxes the packet index once (timestamps and keyframe flags,
no decoding), orders frames by presentation timestamp (so B-frames are handled) and decodes a
requested frame by seeking to the keyframe that precedes it and decoding forward. Files written
by the original RMB carry no frame rate (a player sees ffmpeg's default 25 fps), so frame
numbers come from timestamp order only, never from a frame rate.

Writing: :class:`VideoFileWriter` encodes frame by frame (nothing is buffered), and
:class:`RgbVideoWriter` / :class:`RgbVideoReader` are the RGB image streams of an ``.rmb``
episode (libx264, yuv420p, like the original's ``videoio.videosave``).
"""

from __future__ import annotations

from collections.abc import Iterator
from fractions import Fraction
from pathlib import Path
from typing import Self

import av
import cv2
import numpy as np

from rmb_lerobot.codecs.indexing import FrameIndex, resolve_index
from rmb_lerobot.errors import RmbFormatError

# Nominal frame rate written into new files. The original's files say 25 fps (ffmpeg's default
# for raw input without a rate); readers never use it: the control rate is in the `time` key.
NOMINAL_FPS = 25

# RGB keyframe interval. Reading frame i decodes from the keyframe before it, so a random read
# costs about GOP/2 decoded frames. x264's default (250) makes a random read of a 300-frame
# episode decode ~125 frames; LeRobot's g=2 decodes at most 2 but costs the most bytes.
# Measured on a synthetic 640x480 clip (120 frames, smooth background, moving object, CRF 23):
# g=250 39 KB and 17 ms per random read, g=10 91 KB and 3.7 ms, g=2 172 KB and 1.6 ms. 10 keeps
# reads within a few ms; the bytes it adds are small next to those of depth or camera noise.
RGB_GOP = 10


class _SeekOvershoot(Exception):
    """The demuxer landed after the keyframe we asked for (imprecise container index)."""


class VideoFrameReader:
    """Decoded ``av.VideoFrame``s of the first video stream of an MP4/MKV file, by index.

    Opens the file once and keeps the decoder: consecutive requests continue decoding where
    the previous one stopped instead of seeking again. Not thread-safe; use one per worker.
    """

    def __init__(self, path: str | Path):
        self.path = Path(path)
        if not self.path.is_file():
            raise RmbFormatError("video file not found; expected an MP4/MKV video", path=self.path)
        try:
            self._container = av.open(str(self.path))
        except (av.FFmpegError, OSError) as exc:
            raise RmbFormatError(
                f"cannot open video ({exc}); expected a readable MP4/MKV video", path=self.path
            ) from exc
        try:
            if not self._container.streams.video:
                raise RmbFormatError("no video stream; expected an MP4/MKV video", path=self.path)
            self._stream = self._container.streams.video[0]
            self._scan_packets()
        except BaseException:
            self._container.close()
            raise
        self._frames: Iterator[tuple[int, av.VideoFrame]] | None = None
        self._last_out = -1  # display index of the last frame the decoder returned
        self._last_fed = -1  # decode index of the last packet given to the decoder

    def _scan_packets(self) -> None:
        """Demux once (no decoding): frame count, display order and keyframe of every frame."""
        pts: list[int] = []
        dts: list[int | None] = []
        keyframe: list[bool] = []
        try:
            for packet in self._container.demux(self._stream):
                if packet.size == 0:
                    continue  # end-of-stream marker
                if packet.pts is None:
                    raise RmbFormatError(
                        "video packet without timestamp; expected an MP4/MKV video with pts",
                        path=self.path,
                    )
                pts.append(packet.pts)
                dts.append(packet.dts)
                keyframe.append(packet.is_keyframe)
        except av.FFmpegError as exc:
            raise RmbFormatError(
                f"corrupt video ({exc}); expected a readable MP4/MKV video", path=self.path
            ) from exc
        if not pts:
            raise RmbFormatError("video has no frames; expected at least one", path=self.path)
        if len(set(pts)) != len(pts):
            raise RmbFormatError(
                "video frames share timestamps; expected one frame per timestamp", path=self.path
            )
        # Decode order is demux order; display order is pts order.
        key_of_decoded = np.maximum.accumulate(
            np.where(np.asarray(keyframe), np.arange(len(pts)), 0)
        )
        display_to_decode = np.argsort(np.asarray(pts), kind="stable")
        self._pts = [pts[d] for d in display_to_decode]
        self._display_of_pts = {p: i for i, p in enumerate(self._pts)}
        self._decode_of_pts = {p: d for d, p in enumerate(pts)}
        self._key_decode = [int(key_of_decoded[d]) for d in display_to_decode]
        self._seek_ts = [
            min(pts[d], dts[d]) if dts[d] is not None else pts[d] for d in range(len(pts))
        ]

    def __len__(self) -> int:
        return len(self._pts)

    @property
    def width(self) -> int:
        return self._stream.codec_context.width

    @property
    def height(self) -> int:
        return self._stream.codec_context.height

    def frames(self, index: FrameIndex) -> av.VideoFrame | list[av.VideoFrame]:
        """Frame(s) at ``index`` (int, slice, list or int array; negative counts from the end)."""
        positions, single = resolve_index(index, len(self))
        decoded = {i: self._frame(i) for i in sorted(set(positions))}
        return decoded[positions[0]] if single else [decoded[i] for i in positions]

    def _frame(self, i: int) -> av.VideoFrame:
        key = self._key_decode[i]
        can_continue = self._frames is not None and i > self._last_out
        if not (can_continue and key <= self._last_fed + 1):
            self._restart(key)
        try:
            for display, frame in self._frames:
                if display == i:
                    return frame
                if display > i:
                    break
        except av.FFmpegError as exc:
            self._frames = None
            raise RmbFormatError(
                f"cannot decode frame {i} ({exc}); expected a readable video", path=self.path
            ) from exc
        self._frames = None
        raise RmbFormatError(
            f"frame {i} could not be decoded; expected {len(self)} decodable frames",
            path=self.path,
        )

    def _restart(self, key: int) -> None:
        """Position the decoder at decode index ``key`` (a keyframe)."""
        try:
            self._frames = self._decode_from(key, self._seek_ts[key])
            self._frames = _peekable(self._frames)
        except _SeekOvershoot:
            self._frames = _peekable(self._decode_from(key, None))

    def _decode_from(self, key: int, seek_ts: int | None) -> Iterator[tuple[int, av.VideoFrame]]:
        """Frames (display index, frame) from keyframe ``key`` on; seek_ts None = file start."""
        if seek_ts is None:
            self._container.seek(0)
        else:
            self._container.seek(seek_ts, stream=self._stream, backward=True)
        codec = self._stream.codec_context
        codec.flush_buffers()
        self._last_out, self._last_fed = -1, -1
        started = False
        for packet in self._container.demux(self._stream):
            if packet.size == 0:
                if started:
                    for frame in codec.decode(None):
                        yield self._emit(frame)
                return
            decode_index = self._decode_of_pts.get(packet.pts)
            if not started:
                if decode_index is None or decode_index < key:
                    continue
                if decode_index > key:
                    raise _SeekOvershoot
                started = True
            self._last_fed = decode_index
            for frame in codec.decode(packet):
                yield self._emit(frame)

    def _emit(self, frame: av.VideoFrame) -> tuple[int, av.VideoFrame]:
        display = self._display_of_pts.get(frame.pts)
        if display is None:
            raise RmbFormatError(
                f"decoded frame has unknown timestamp {frame.pts}; expected one of the "
                "packet timestamps",
                path=self.path,
            )
        self._last_out = display
        return display, frame

    def close(self) -> None:
        self._frames = None
        self._container.close()

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _peekable(frames: Iterator[tuple[int, av.VideoFrame]]) -> Iterator[tuple[int, av.VideoFrame]]:
    """Start the generator now so that a seek overshoot is raised inside ``_restart``."""
    first = next(frames, None)

    def chained() -> Iterator[tuple[int, av.VideoFrame]]:
        if first is not None:
            yield first
            yield from frames

    return chained()


class VideoFileWriter:
    """Incremental encoder: one ``av.VideoFrame`` in, packets muxed as they come out."""

    def __init__(
        self,
        path: str | Path,
        width: int,
        height: int,
        *,
        codec: str,
        pix_fmt: str,
        options: dict[str, str],
        fps: int = NOMINAL_FPS,
    ):
        self.path = Path(path)
        self.width, self.height = int(width), int(height)
        if self.width <= 0 or self.height <= 0:
            raise RmbFormatError(
                f"bad frame size {width}x{height}; expected positive width and height",
                path=self.path,
            )
        container_format = "matroska" if self.path.suffix.lower() == ".mkv" else "mp4"
        self._container = av.open(str(self.path), "w", format=container_format)
        try:
            self._stream = self._container.add_stream(codec, rate=fps, options=options)
            self._stream.width, self._stream.height = self.width, self.height
            self._stream.pix_fmt = pix_fmt
            self._stream.codec_context.time_base = Fraction(1, fps)
        except BaseException:
            self._container.close()
            raise
        self._count = 0
        self._closed = False

    def __len__(self) -> int:
        return self._count

    def encode(self, frame: av.VideoFrame) -> None:
        if self._closed:
            raise RmbFormatError("writer is closed; expected no more frames", path=self.path)
        frame.pts = self._count
        frame.time_base = self._stream.codec_context.time_base
        for packet in self._stream.encode(frame):
            self._container.mux(packet)
        self._count += 1

    def close(self) -> None:
        """Flush the encoder and finish the file (idempotent)."""
        if self._closed:
            return
        self._closed = True
        try:
            for packet in self._stream.encode(None):
                self._container.mux(packet)
        finally:
            self._container.close()


class RgbVideoWriter:
    """H.264 (libx264, yuv420p) MP4 of uint8 RGB frames, encoded as they arrive.

    Same stream as the original's ``videoio.videosave`` (libx264, yuv420p, CRF 23 by default;
    the original used preset "slow"), plus a short keyframe interval for random access.
    """

    def __init__(
        self,
        path: str | Path,
        width: int,
        height: int,
        *,
        preset: str = "medium",
        crf: int = 23,
        gop: int = RGB_GOP,
    ):
        options = {"crf": str(crf), "preset": preset, "g": str(gop)}
        self._video = VideoFileWriter(
            path, width, height, codec="libx264", pix_fmt="yuv420p", options=options
        )
        self.path = self._video.path

    def write(self, frame: np.ndarray) -> None:
        """Encode one (H, W, 3) uint8 RGB frame."""
        shape = (self._video.height, self._video.width, 3)
        if not isinstance(frame, np.ndarray) or frame.dtype != np.uint8 or frame.shape != shape:
            got = (
                f"{frame.dtype} {frame.shape}"
                if isinstance(frame, np.ndarray)
                else type(frame).__name__
            )
            raise RmbFormatError(
                f"bad RGB frame {len(self._video)}: got {got}, expected uint8 {shape}",
                path=self.path,
            )
        self._video.encode(av.VideoFrame.from_ndarray(np.ascontiguousarray(frame), format="rgb24"))

    def __len__(self) -> int:
        return len(self._video)

    def close(self) -> None:
        self._video.close()

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


class RgbVideoReader:
    """uint8 RGB frames of a video by index; ``image_size=(w, h)`` resizes like RMB's loader."""

    def __init__(self, path: str | Path, image_size: tuple[int, int] | None = None):
        self._video = VideoFrameReader(path)
        self.path = self._video.path
        self.image_size = None if image_size is None else (int(image_size[0]), int(image_size[1]))

    def __len__(self) -> int:
        return len(self._video)

    @property
    def shape(self) -> tuple[int, int, int, int]:
        width, height = self.image_size or (self._video.width, self._video.height)
        return (len(self), height, width, 3)

    def __getitem__(self, index: FrameIndex) -> np.ndarray:
        """(H, W, 3) for an int, (N, H, W, 3) for a slice or list."""
        frames = self._video.frames(index)
        if isinstance(frames, av.VideoFrame):
            return self._to_rgb(frames)
        if not frames:
            return np.empty((0, *self.shape[1:]), dtype=np.uint8)
        return np.stack([self._to_rgb(f) for f in frames])

    def _to_rgb(self, frame: av.VideoFrame) -> np.ndarray:
        image = frame.to_ndarray(format="rgb24")
        if self.image_size is not None and self.image_size != (image.shape[1], image.shape[0]):
            image = cv2.resize(image, self.image_size, interpolation=cv2.INTER_LINEAR)
        return image

    def close(self) -> None:
        self._video.close()

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
