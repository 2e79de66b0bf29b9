"""Depth codecs compared on synthetic 640x480 depth: size, error, speed, random access.

Codecs: the original RMB depth video (``rmb-videoio`` with x264's default GOP 250, exactly as
RMB writes it, and with the GOP 30 our writer uses), ours (``rmbz``, ``rmbz-exact``), and
LeRobot 0.6.1's depth encoding (12-bit log quantisation, lossless HEVC gray12le, g=2; its own
``quantize_depth`` / ``decode_video_frames_pyav`` / ``dequantize_depth``).

Content (rmb_lerobot.codecs.synthetic): ``clean`` = rendered-like (floor + box + moving sphere,
exact depth rounded to mm); ``noisy`` = the same + N(0, 2 mm * z^2) + 1 % dropouts (0).

    .venv/bin/python benchmarks/depth_codecs.py            # 220-frame sequences, 300-frame episode
    .venv/bin/python benchmarks/depth_codecs.py --quick    # 40 / 60 frames, a smoke test
    .venv/bin/python benchmarks/depth_codecs.py --frames 100 --no-lerobot
"""

from __future__ import annotations

import argparse
import tempfile
import time
from collections.abc import Callable
from fractions import Fraction
from pathlib import Path

import av
import numpy as np

from rmb_lerobot.codecs.depth import get_depth_codec
from rmb_lerobot.codecs.synthetic import clean_depth_mm, noisy_depth_mm
from rmb_lerobot.codecs.videoio_depth import VideoioDepthCodec

WIDTH, HEIGHT = 640, 480
BASELINE = "rmb-videoio g=250 (original)"
CONTENTS = {"clean": clean_depth_mm, "noisy": noisy_depth_mm}


class LeRobotDepth:
    """LeRobot's DepthEncoderConfig pipeline, driven through LeRobot's own functions."""

    fps = 30  # LeRobot needs a frame rate for its timestamps; any value works here

    def __init__(self):
        from lerobot.configs.video import DepthEncoderConfig

        # Defaults (hevc, gray12le, g=2, lossless x265); only x265's console log is silenced.
        self.config = DepthEncoderConfig(
            extra_options={"x265-params": "lossless=1:log-level=error"}
        )

    def encode(self, path: Path, frames: list[np.ndarray]) -> None:
        from lerobot.datasets.depth_utils import quantize_depth

        cfg = self.config
        with av.open(str(path), "w") as container:
            options = cfg.get_codec_options(as_strings=True)
            stream = container.add_stream(cfg.vcodec, self.fps, options=options)
            stream.pix_fmt, stream.width, stream.height = cfg.pix_fmt, WIDTH, HEIGHT
            stream.time_base = Fraction(1, self.fps)
            for i, frame in enumerate(frames):
                video_frame = quantize_depth(
                    frame,
                    depth_min=cfg.depth_min,
                    depth_max=cfg.depth_max,
                    shift=cfg.shift,
                    use_log=cfg.use_log,
                    pix_fmt=cfg.pix_fmt,
                )
                video_frame.pts, video_frame.time_base = i, Fraction(1, self.fps)
                for packet in stream.encode(video_frame):
                    container.mux(packet)
            for packet in stream.encode(None):
                container.mux(packet)

    def decode(self, path: Path, indices: list[int]) -> np.ndarray:
        """LeRobot opens the video for every query, like its dataset loader does."""
        from lerobot.datasets.depth_utils import dequantize_depth
        from lerobot.datasets.video_utils import decode_video_frames_pyav

        cfg = self.config
        timestamps = [i / self.fps for i in indices]
        codes = decode_video_frames_pyav(path, timestamps, 0.5 / self.fps, is_depth=True)
        mm = dequantize_depth(
            codes,
            depth_min=cfg.depth_min,
            depth_max=cfg.depth_max,
            shift=cfg.shift,
            use_log=cfg.use_log,
            output_unit="mm",
            output_tensor=False,
        )
        return mm[:, 0]


class Bench:
    """One codec behind three calls: encode a list of frames, open a reader, decode indices."""

    def __init__(self, name: str, suffix: str, encode, open_reader: Callable | None, lerobot=None):
        self.name, self.suffix = name, suffix
        self._encode, self._open, self._lerobot = encode, open_reader, lerobot

    def encode(self, path: Path, frames: list[np.ndarray]) -> None:
        self._encode(path, frames)

    def reader(self, path: Path):
        """A persistent reader (or None for LeRobot, which reopens the file per query)."""
        return None if self._open is None else self._open(path)

    def read(self, path: Path, indices: list[int], reader=None) -> np.ndarray:
        if self._lerobot is not None:
            return self._lerobot.decode(path, indices)
        if reader is not None:
            return reader[indices]
        with self._open(path) as fresh:
            return fresh[indices]


def ours(name: str, codec) -> Bench:
    def encode(path, frames):
        with codec.writer(path, WIDTH, HEIGHT) as writer:
            for frame in frames:
                writer.write(frame)

    return Bench(name, codec.file_suffix, encode, codec.reader)


def benches(include_lerobot: bool) -> list[Bench]:
    out = [
        ours(BASELINE, VideoioDepthCodec(gop=None)),
        ours("rmb-videoio g=30 (our writer)", get_depth_codec("rmb-videoio")),
        ours("rmbz", get_depth_codec("rmbz")),
        ours("rmbz-exact", get_depth_codec("rmbz-exact")),
    ]
    if include_lerobot:
        lerobot = LeRobotDepth()
        name = "lerobot hevc gray12 log (g=2)"
        out.append(Bench(name, ".mp4", lerobot.encode, None, lerobot))
    return out


def timed(fn, *args):
    start = time.perf_counter()
    result = fn(*args)
    return result, time.perf_counter() - start


def random_reads(bench: Bench, path: Path, n: int, count: int, seed: int) -> tuple[float, float]:
    """Mean seconds per random frame: (fresh reader each time, one persistent reader)."""
    indices = np.random.default_rng(seed).integers(0, n, count).tolist()
    start = time.perf_counter()
    for i in indices:
        bench.read(path, [i])
    fresh = (time.perf_counter() - start) / count
    reader = bench.reader(path)
    if reader is None:
        return fresh, fresh
    with reader:
        start = time.perf_counter()
        for i in indices:
            bench.read(path, [i], reader)
        persistent = (time.perf_counter() - start) / count
    return fresh, persistent


def size_table(tmp: Path, benches: list[Bench], n: int, reads: int) -> list[str]:
    rows = [
        "| content | codec | MB | x original | mean err mm | max err mm | zeros kept | "
        "encode fps | decode fps | random read ms fresh / persistent |",
        "|---|---|---:|---:|---:|---:|---|---:|---:|---:|",
    ]
    print("\n".join(rows), flush=True)
    for content, generate in CONTENTS.items():
        frames = list(generate(n, WIDTH, HEIGHT))
        truth = np.stack(frames).astype(np.int32)
        baseline_size = None
        for bench in benches:
            path = tmp / f"{content}-{len(rows)}{bench.suffix}"
            _, t_enc = timed(bench.encode, path, frames)
            decoded, t_dec = timed(bench.read, path, list(range(n)))
            size = path.stat().st_size
            baseline_size = baseline_size or size
            error = np.abs(decoded.astype(np.int32) - truth)
            holes = truth == 0
            zeros = ("yes" if (decoded[holes] == 0).all() else "no") if holes.any() else "n/a"
            fresh, persistent = random_reads(bench, path, n, reads, seed=1)
            rows.append(
                f"| {content} | {bench.name} | {size / 1e6:.3f} | {size / baseline_size:.2f} | "
                f"{error.mean():.3f} | {error.max()} | {zeros} | "
                f"{n / t_enc:.1f} | {n / t_dec:.1f} | {fresh * 1e3:.1f} / {persistent * 1e3:.1f} |"
            )
            print(rows[-1], flush=True)
    return rows


def episode_table(tmp: Path, benches: list[Bench], n: int, reads: int) -> list[str]:
    rows = [
        "| content | codec | whole-file decode s | random frame ms (fresh reader) | "
        "speedup vs own whole file | speedup vs original whole file |",
        "|---|---|---:|---:|---:|---:|",
    ]
    print("\n".join(rows), flush=True)
    for content, generate in CONTENTS.items():
        frames = list(generate(n, WIDTH, HEIGHT))
        original_whole = None
        for bench in benches:
            path = tmp / f"episode-{content}-{len(rows)}{bench.suffix}"
            bench.encode(path, frames)
            _, whole = timed(bench.read, path, list(range(n)))
            original_whole = original_whole or whole
            fresh, _ = random_reads(bench, path, n, reads, seed=2)
            rows.append(
                f"| {content} | {bench.name} | {whole:.2f} | {fresh * 1e3:.1f} | "
                f"{whole / fresh:.0f}x | {original_whole / fresh:.0f}x |"
            )
            print(rows[-1], flush=True)
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=220, help="frames per size/error sequence")
    parser.add_argument("--episode-frames", type=int, default=300, help="frames of the episode")
    parser.add_argument("--reads", type=int, default=10, help="random frames to time")
    parser.add_argument("--quick", action="store_true", help="40/60 frames, 5 reads")
    parser.add_argument("--no-lerobot", action="store_true", help="skip LeRobot's encoding")
    args = parser.parse_args()
    if args.quick:
        args.frames, args.episode_frames, args.reads = 40, 60, 5
    all_benches = benches(not args.no_lerobot)
    with tempfile.TemporaryDirectory() as tmp:
        print(f"## {args.frames}-frame 640x480 sequences (ratios vs {BASELINE})\n")
        size_table(Path(tmp), all_benches, args.frames, args.reads)
        print(f"\n## Random access in a {args.episode_frames}-frame 640x480 episode\n")
        # The original against ours; the other codecs' random reads are in the first table.
        episode = [b for b in all_benches if b.name in (BASELINE, "rmbz")]
        episode_table(Path(tmp), episode, args.episode_frames, args.reads)


if __name__ == "__main__":
    main()
