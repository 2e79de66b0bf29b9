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

import threading
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

# Pixel format of RMB's depth videos (videoio uint16 scheme); never that of its RGB videos.
DEPTH_VIDEO_PIX_FMT = "yuv444p"


class _SeekOvershoot(Exception):
    """The demuxer landed after the keyframe we asked for (imprecise container index)."""


# Decoder settings that turn corrupt input into errors instead of plausible-looking frames:
# libavcodec's H.264 decoder conceals damaged macroblocks by default (it copies neighbours and
# carries on), and with slice threading (PyAV's default) it drops even the errors that
# `explode` would raise. One thread costs nothing here: x264 writes one slice per frame, so
# slice threads had nothing to run in parallel.
DECODER_OPTIONS = {"err_detect": "crccheck+bitstream+buffer+explode", "ec": "0"}

_log_lock = threading.Lock()
_log_users = 0
_log_previous: int | None = None


class _LibavErrors:
    """Errors libav reports while the block runs: ``with _LibavErrors() as log: ...``.

    Decoders and demuxers report much of the damage they meet only through libav's log
    (a concealed macroblock, an inconsistent sample table). PyAV drops that log by default,
    so the level is raised to ERROR while any reader is inside such a block (and put back
    when the last one leaves); this thread's messages are captured rather than printed.
    Errors are counted with libav's own counter, which also sees messages the log
    de-duplicates (reading a corrupt frame twice logs the same line twice). The counter is
    process-wide: another thread decoding a damaged stream at the same moment would make this
    block report its error too (never the reverse: no corruption is missed).
    """

    def __enter__(self) -> _LibavErrors:
        global _log_users, _log_previous
        with _log_lock:
            if _log_users == 0:
                _log_previous = av.logging.get_level()
                if _log_previous is None or _log_previous < av.logging.ERROR:
                    av.logging.set_level(av.logging.ERROR)
            _log_users += 1
        self._count = av.logging.get_last_error()[0]
        self._capture = av.logging.Capture()
        self._logs = self._capture.__enter__()
        return self

    def messages(self) -> list[str]:
        """Messages at ERROR level or worse logged so far inside the block."""
        found = [msg.strip() for level, _, msg in self._logs if level <= av.logging.ERROR]
        count, last = av.logging.get_last_error()
        if count > self._count and not found and last is not None:
            found.append(last[2].strip())  # repeated line, not passed on by the log
        return found

    def __exit__(self, *exc) -> None:
        global _log_users
        self._capture.__exit__(*exc)
        with _log_lock:
            _log_users -= 1
            if _log_users == 0 and av.logging.get_level() != _log_previous:
                av.logging.set_level(_log_previous)


class VideoFrameReader:
    """Decoded ``av.VideoFrame``s of the first video stream of an MP4/MKV file, by index.

    Opens the file once and keeps the decoder: consecutive requests continue decoding where
    the previous one stopped instead of seeking again. Not thread-safe; use one per worker.

    Corruption is an :class:`RmbFormatError` naming the file and the frame, whenever the
    file itself shows it: libav errors while opening, demuxing or decoding (the decoder is
    set to report errors instead of concealing them, see :data:`DECODER_OPTIONS`), packets
    flagged corrupt, packets or frames that disagree with the index built at open (count,
    order, timestamps), frames whose size or pixel format differ from the stream's. What
    stays undetectable is damage that leaves a syntactically valid stream: a flipped bit
    in a residual coefficient, a motion vector or a quantiser of lossy H.264 decodes to a
    wrong but well-formed frame (and the frames predicted from it), and a flip in bytes
    the decoder never reads changes nothing at all. Codec-level checks of the payload
    (the ``videoio`` depth scheme's empty U plane, the checksums of ``rmbz``) catch more.
    """

    def __init__(self, path: str | Path):
        self.path = Path(path)
        if not self.path.is_file():
            raise RmbFormatError("video file not found; expected an MP4/MKV video", path=self.path)
        with _LibavErrors() as log:
            try:
                # Metadata (handler names, encoder tags) is never used: undecodable bytes there
                # must not make the frames unreadable.
                self._container = av.open(str(self.path), metadata_errors="replace")
            except (av.FFmpegError, OSError, UnicodeDecodeError) as exc:
                raise self._bad(f"cannot open video ({exc})", log) from exc
            try:
                self._open_stream()
                self._scan_packets()
                if log.messages():
                    raise self._bad("corrupt video: errors while opening it", log)
            except BaseException:
                self._container.close()
                raise
        self._frames: Iterator[tuple[int, av.VideoFrame]] | None = None
        self._last_out = -1  # display index of the last frame the decoder returned
        self._last_fed = -1  # decode index of the last packet given to the decoder

    def _bad(self, what: str, log: _LibavErrors | None = None) -> RmbFormatError:
        messages = log.messages() if log is not None else []
        said = f" (libav: {'; '.join(dict.fromkeys(messages))[:300]})" if messages else ""
        return RmbFormatError(f"{what}{said}; expected a readable MP4/MKV video", path=self.path)

    def _open_stream(self) -> None:
        if not self._container.streams.video:
            raise self._bad("no video stream")
        self._stream = self._container.streams.video[0]
        codec = self._stream.codec_context
        if codec is None:
            raise self._bad("no decoder for the video stream's codec")
        if codec.width <= 0 or codec.height <= 0 or codec.pix_fmt is None:
            raise self._bad(
                f"video stream has no frame size or pixel format ({codec.width}x"
                f"{codec.height}, {codec.pix_fmt})"
            )
        codec.options = dict(DECODER_OPTIONS)
        codec.thread_count = 1
        self._size = (codec.width, codec.height)
        self.pix_fmt: str = codec.pix_fmt

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
                    raise self._bad("video packet without timestamp")
                if packet.is_corrupt:
                    raise self._bad(f"video packet {len(pts)} is flagged corrupt by the demuxer")
                pts.append(packet.pts)
                dts.append(packet.dts)
                keyframe.append(packet.is_keyframe)
        except av.FFmpegError as exc:
            raise self._bad(f"corrupt video ({exc})") from exc
        if not pts:
            raise self._bad("video has no frames")
        if not keyframe[0]:
            raise self._bad("the first video packet is not a keyframe")
        if len(set(pts)) != len(pts):
            raise self._bad("video frames share timestamps")
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
        return self._size[0]

    @property
    def height(self) -> int:
        return self._size[1]

    @property
    def time_base(self) -> Fraction:
        """Seconds per timestamp unit of the stream (a frame's time is ``pts * time_base``)."""
        return self._stream.time_base

    def frames(self, index: FrameIndex) -> av.VideoFrame | list[av.VideoFrame]:
        """Frame(s) at ``index`` (int, slice, list or int array; negative counts from the end)."""
        positions, single = resolve_index(index, len(self))
        decoded = {i: self._frame(i) for i in sorted(set(positions))}
        return decoded[positions[0]] if single else [decoded[i] for i in positions]

    def _frame(self, i: int) -> av.VideoFrame:
        with _LibavErrors() as log:
            try:
                frame = self._find(i)
            except av.FFmpegError as exc:
                self._frames = None
                raise self._corrupt(i, str(exc), log) from exc
            except RmbFormatError:
                self._frames = None
                raise
            if frame is None:
                self._frames = None
                raise self._corrupt(i, f"no such frame in the decoder's output of {len(self)}")
            if log.messages():
                self._frames = None  # the decoder state is damaged: start afresh next time
                raise self._corrupt(i, "the decoder reported errors", log)
        return frame

    def _corrupt(self, i: int, what: str, log: _LibavErrors | None = None) -> RmbFormatError:
        key = self._key_decode[i]
        messages = log.messages() if log is not None else []
        said = f" (libav: {'; '.join(dict.fromkeys(messages))[:300]})" if messages else ""
        return RmbFormatError(
            f"video frame {i} is corrupt: {what}{said} while decoding from the keyframe at "
            f"packet {key}; expected {len(self)} decodable frames",
            path=self.path,
        )

    def _find(self, i: int) -> av.VideoFrame | None:
        """Decode up to display index ``i``; None if the decoder went past it without it."""
        key = self._key_decode[i]
        can_continue = self._frames is not None and i > self._last_out
        if not (can_continue and key <= self._last_fed + 1):
            self._restart(key)
        for display, frame in self._frames:
            if display == i:
                return frame
            if display > i:
                break
        return None

    def _restart(self, key: int) -> None:
        """Position the decoder at decode index ``key`` (a keyframe)."""
        self._frames = None
        try:
            frames = _peekable(self._decode_from(key, self._seek_ts[key]))
        except _SeekOvershoot:
            frames = _peekable(self._decode_from(key, None))
        self._frames = frames

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
            elif decode_index != self._last_fed + 1 or packet.is_corrupt:
                raise RmbFormatError(
                    f"video packet after {self._last_fed} (pts {packet.pts}) differs from the "
                    "packet index read at open; expected the same packets every time",
                    path=self.path,
                )
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
        if display <= self._last_out:
            raise RmbFormatError(
                f"the decoder returned frame {display} after frame {self._last_out}: the "
                "container's timestamps disagree with the H.264 stream's frame order",
                path=self.path,
            )
        if (frame.width, frame.height) != self._size or frame.format.name != self.pix_fmt:
            raise RmbFormatError(
                f"video frame {display} decoded to {frame.width}x{frame.height} "
                f"{frame.format.name}; expected the stream's {self._size[0]}x{self._size[1]} "
                f"{self.pix_fmt}",
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
    """uint8 RGB frames of a video by index; ``image_size=(w, h)`` resizes like RMB's loader.

    Refuses yuv444p streams: RMB writes RGB as yuv420p and depth as yuv444p (U = 0), so a
    yuv444p RGB file is a depth video in the wrong place, whose frames would read as
    green-purple noise.
    """

    def __init__(self, path: str | Path, image_size: tuple[int, int] | None = None):
        self._video = VideoFrameReader(path)
        self.path = self._video.path
        if self._video.pix_fmt == DEPTH_VIDEO_PIX_FMT:
            self._video.close()
            raise RmbFormatError(
                f"RGB video stream is {DEPTH_VIDEO_PIX_FMT}, the format of RMB depth videos "
                "(is a depth video in this RGB file's place?); expected yuv420p H.264 "
                "(RMB's videoio.videosave)",
                path=self.path,
            )
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
