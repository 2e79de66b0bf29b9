"""``--video-codec copy``: RMB's H.264 RGB packets go into the dataset as they are.

A compact ``.rmb`` episode stores each RGB camera as H.264 (yuv420p) in MP4, which LeRobot
decodes as well as its own AV1. Copying the packets skips the encoder (the dominant cost of a
conversion) and the second generation of compression loss: the dataset holds the recorded
frames bit for bit. Only timestamps change: frame ``k`` gets ``pts = k`` in a time base of
``1 / rate`` (the original's files say 25 fps; the rate comes from the ``time`` key), which is
what LeRobot's writer produces too, so its concatenation and timestamp lookup work unchanged.

What it costs: random access in training decodes from the previous keyframe, so it is as fast
as the source's keyframe interval allows (our writer: 10; the original RMB's x264 default: 250,
which makes training-time decoding slow: re-encode those with LeRobot's codecs instead).
Copying needs every episode's stream of a camera to share one codec configuration (size,
pixel format, SPS/PPS), since LeRobot concatenates episodes into one file by stream copy.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

import av
import numpy as np
from av.bitstream import BitStreamFilterContext

from rmb_lerobot import keys as K
from rmb_lerobot.converters.plan import ConversionPlan
from rmb_lerobot.episode import EpisodeFormat, episode_format
from rmb_lerobot.episode.layout import rgb_video_path
from rmb_lerobot.errors import RmbFormatError

COPY = "copy"  # the --video-codec value
COPYABLE_CODEC = "h264"
COPYABLE_PIX_FMT = "yuv420p"


@dataclass(frozen=True)
class StreamConfig:
    """What must match for two H.264 streams to be concatenated by stream copy."""

    codec: str
    width: int
    height: int
    pix_fmt: str
    extradata: bytes


def stream_config(path: Path) -> StreamConfig:
    try:
        with av.open(str(path)) as container:
            context = container.streams.video[0].codec_context
            return StreamConfig(
                context.name,
                context.width,
                context.height,
                context.pix_fmt,
                bytes(context.extradata or b""),
            )
    except (av.FFmpegError, IndexError) as exc:
        raise RmbFormatError(f"cannot read the video stream: {exc}", path=path) from exc


def keyframe_interval(path: Path) -> int:
    """Largest distance between keyframes (the cost of a random frame read, in frames)."""
    with av.open(str(path)) as container:
        stream = container.streams.video[0]
        keys = [i for i, p in enumerate(container.demux(stream)) if p.size and p.is_keyframe]
    return int(max(np.diff([*keys, keys[-1] + 1]))) if keys else 1


def check_copyable(plan: ConversionPlan) -> int:
    """Raise unless every RGB stream can be copied; returns the largest keyframe interval."""
    if plan.skip != 1:
        raise RmbFormatError(f"--video-codec {COPY} keeps every frame; it cannot --skip")
    gop = 1
    for camera in plan.schema.cameras:
        first: tuple[Path, StreamConfig] | None = None
        for episode in plan.episodes:
            if episode_format(episode.path) is not EpisodeFormat.COMPACT:
                raise RmbFormatError(
                    f"--video-codec {COPY} needs compact .rmb episodes (RGB stored as video)",
                    path=episode.path,
                )
            path = rgb_video_path(episode.path, K.rgb_image_key(camera))
            config = stream_config(path)
            if config.codec != COPYABLE_CODEC or config.pix_fmt != COPYABLE_PIX_FMT:
                raise RmbFormatError(
                    f"--video-codec {COPY} needs {COPYABLE_CODEC} {COPYABLE_PIX_FMT} video, got "
                    f"{config.codec} {config.pix_fmt}",
                    path=path,
                    key=K.rgb_image_key(camera),
                )
            if first is None:
                first = (path, config)
                gop = max(gop, keyframe_interval(path))
            elif config != first[1]:
                raise RmbFormatError(
                    f"--video-codec {COPY}: this stream's encoder settings differ from "
                    f"{str(first[0])!r}, so they cannot share one video file; re-encode instead",
                    path=path,
                    key=K.rgb_image_key(camera),
                )
    return gop


def remux(src: Path, dst: Path, rate: Fraction, frames: int) -> None:
    """Copy the video packets of ``src`` into ``dst`` with frame ``k`` at ``k / rate``.

    The H.264 stream also states a frame rate (SPS timing info; 25 fps in RMB's files), which
    demuxers use for packet durations: FFmpeg's ``h264_metadata`` filter rewrites it to
    ``rate``, or LeRobot's episode concatenation would place each next episode a fraction of a
    frame late.
    """
    with av.open(str(src)) as source:
        stream = source.streams.video[0]
        packets = [p for p in source.demux(stream) if p.size and p.pts is not None]
        if len(packets) != frames:
            raise RmbFormatError(
                f"video has {len(packets)} frames but {frames} were converted", path=src
            )
        pts = np.sort([p.pts for p in packets])
        step = int(np.median(np.diff(pts))) if len(pts) > 1 else 1
        if len(pts) > 1 and np.any((pts - pts[0]) % step):
            raise RmbFormatError("frames are not evenly spaced in time; cannot copy", path=src)
        time_base = 1 / Fraction(rate)
        with av.open(str(dst), "w") as out:
            target = out.add_stream_from_template(stream)
            target.time_base = time_base
            timing = BitStreamFilterContext(f"h264_metadata=tick_rate={2 * rate}", stream, target)
            for packet in packets:
                dts = packet.pts if packet.dts is None else packet.dts
                new_pts, new_dts = (packet.pts - int(pts[0])) // step, (dts - int(pts[0])) // step
                packet.time_base = time_base
                packet.pts, packet.dts, packet.duration = new_pts, new_dts, 1
                _mux(out, target, timing.filter(packet))
            _mux(out, target, timing.filter(None))


def _mux(out, stream, packets) -> None:
    for packet in packets:
        packet.stream = stream
        out.mux(packet)
