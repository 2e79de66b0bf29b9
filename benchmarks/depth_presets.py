"""x265 presets for LeRobot's lossless depth videos: CPU per frame and bytes at equal output.

Usage::

    .venv/bin/python benchmarks/depth_presets.py [--frames 40] [--presets ultrafast ... medium]
        [--threads 1]

LeRobot 0.6.1 stores depth as 12-bit codes (its ``quantize_depth``: log quantisation of
0.01..10 m) in lossless HEVC (``gray12le``, g=2, ``x265-params lossless=1``) at x265's default
preset (``medium``). Lossless means every preset decodes to the same codes; presets trade only
encoding CPU against bytes. Each preset encodes the same synthetic 640x480 frames
(:mod:`rmb_lerobot.codecs.synthetic`: rendered-like ``clean`` and sensor-like ``noisy``) through
LeRobot's own encoder options (:class:`~lerobot.configs.DepthEncoderConfig` with ``preset``
set), the video is decoded with PyAV and compared with the quantised input code for code (an
error if any differs). Reported: CPU ms per frame (this process, all threads; ``--threads 1``
by default so that it is the work, not the parallelism), wall ms per frame, bytes per frame,
and ratios to ``medium``. Rounds of the presets alternate (``--repeats``), medians reported.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from fractions import Fraction
from pathlib import Path

import av
import numpy as np
from lerobot.configs import DepthEncoderConfig
from lerobot.datasets.depth_utils import quantize_depth

from rmb_lerobot.codecs.synthetic import clean_depth_mm, noisy_depth_mm

PRESETS = ("ultrafast", "superfast", "veryfast", "faster", "fast", "medium")
CONTENTS = {"clean": clean_depth_mm, "noisy": noisy_depth_mm}
FPS = 30


def encode(path: Path, codes: list[np.ndarray], preset: str, threads: int | None) -> None:
    """Write 12-bit codes as LeRobot's depth video, with ``preset`` (LeRobot's option path)."""
    config = DepthEncoderConfig(
        preset=preset, extra_options={"x265-params": "lossless=1:log-level=error"}
    )
    height, width = codes[0].shape
    with av.open(str(path), "w") as container:
        options = config.get_codec_options(threads, as_strings=True)
        stream = container.add_stream(config.vcodec, FPS, options=options)
        stream.pix_fmt, stream.width, stream.height = config.pix_fmt, width, height
        stream.time_base = Fraction(1, FPS)
        for i, code in enumerate(codes):
            frame = av.VideoFrame.from_ndarray(code, format=config.pix_fmt)
            frame.pts, frame.time_base = i, Fraction(1, FPS)
            container.mux(stream.encode(frame))
        container.mux(stream.encode(None))


def decode(path: Path) -> np.ndarray:
    with av.open(str(path)) as container:
        return np.stack([f.to_ndarray() for f in container.decode(video=0)])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=40)
    parser.add_argument("--presets", nargs="+", default=list(PRESETS))
    parser.add_argument("--threads", type=int, default=1, help="x265 threads (0: x265's choice)")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    threads = args.threads or None
    print(
        f"{args.frames} frames 640x480 per content, x265 threads {threads or 'auto'}, "
        f"{args.repeats} alternating rounds, medians; every preset decodes to the input codes"
    )
    print(
        "| content | preset | CPU ms/frame | wall ms/frame | kB/frame | CPU vs medium | "
        "bytes vs medium |"
    )
    print("|---|---|---:|---:|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as tmp:
        for content, frames in CONTENTS.items():
            codes = [
                quantize_depth(mm, video_backend=None, input_unit="mm")
                for mm in frames(args.frames)
            ]
            expected = np.stack(codes)
            times: dict[str, list[tuple[float, float]]] = {p: [] for p in args.presets}
            sizes: dict[str, int] = {}
            for _ in range(args.repeats):
                for preset in args.presets:
                    path = Path(tmp) / f"{content}_{preset}.mp4"
                    wall, cpu = time.perf_counter(), time.process_time()
                    encode(path, codes, preset, threads)
                    times[preset].append((time.process_time() - cpu, time.perf_counter() - wall))
                    sizes[preset] = path.stat().st_size
                    if not np.array_equal(decode(path), expected):
                        raise AssertionError(f"{preset} did not decode to the input ({content})")
            rows = {
                p: (
                    statistics.median(t[0] for t in v) * 1e3 / args.frames,
                    statistics.median(t[1] for t in v) * 1e3 / args.frames,
                    sizes[p] / args.frames / 1e3,
                )
                for p, v in times.items()
            }
            base = rows.get("medium", next(iter(rows.values())))
            for preset, (cpu, wall, kb) in rows.items():
                print(
                    f"| {content} | {preset} | {cpu:.1f} | {wall:.1f} | {kb:.1f} | "
                    f"{cpu / base[0]:.2f} | {kb / base[2]:.2f} |"
                )


if __name__ == "__main__":
    main()
