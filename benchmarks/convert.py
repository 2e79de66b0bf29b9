"""``rmb-convert to-lerobot`` throughput, against pure decoding and a PNG round-trip converter.

Usage::

    .venv/bin/python benchmarks/convert.py [--episodes 2] [--steps 100] [--size 640 480]
        [--cameras front hand] [--workdir DIR] [--workers-row] [--depth-only]

Source: synthetic UR5e episodes (:mod:`rmb_lerobot.synthetic`: RGB + depth per camera at RMB's
31.25 Hz) written as compact ``.rmb`` episodes with the original's codecs (H.264 RGB, lossless
``rmb-videoio`` depth). Every row converts the same episodes into the same features:

- ``decode only``: ``open_episode`` and reading every frame of every converted image stream in
  order, plus the low-dimensional keys; the floor for any converter that re-encodes.
- ``ours (LeRobot's AV1)``: :func:`rmb_lerobot.converters.to_lerobot` with LeRobot's default
  RGB codec (frames streamed into LeRobot's encoder threads at the exact rate, no image files).
- ``ours (--video-codec copy)``: the same, RGB packets copied (frames still decoded, for
  LeRobot's image statistics); depth is encoded in both.
- ``PNG round trip``: an imitation of the converter the issue describes for the original RMB
  (decode, write PNGs, re-encode): each episode decoded whole into RAM (as RMB's loader does),
  then LeRobot's default ``add_frame`` path, which writes every frame as a PNG (depth: TIFF)
  and encodes them in ``save_episode`` (one process per camera, LeRobot's default), with the
  same encoder settings, except that depth keeps x265's default preset (LeRobot's; ours uses
  :data:`rmb_lerobot.converters.write.DEPTH_PRESET`, same lossless codes). It runs at fps 31
  because that path cannot encode 31.25 Hz.
- ``ours (copy, --workers 2)``: ``--video-codec copy`` with two worker processes (episodes in
  parallel, merged afterwards); only with ``--workers-row``.

Reported per row: frames per second (episode steps, wall clock), CPU seconds per 100 frames
(this process and its children: robust to other jobs on the machine), and ratios. Depth rows
add the two depth streams (LeRobot's 12-bit HEVC depth encoder).
"""

from __future__ import annotations

import argparse
import resource
import shutil
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
from lerobot.datasets.lerobot_dataset import LeRobotDataset

from rmb_lerobot import EpisodeWriter, find_episodes, open_episode
from rmb_lerobot import keys as K
from rmb_lerobot.converters import ConvertOptions, to_lerobot
from rmb_lerobot.converters.copy import COPY
from rmb_lerobot.converters.plan import plan_conversion
from rmb_lerobot.converters.write import quiet_depth_encoder
from rmb_lerobot.kinematics import UR5E
from rmb_lerobot.synthetic import ur5e_attrs, ur5e_steps

LEROBOT_INT_FPS = 31  # what an integer-fps converter must write for RMB's 31.25 Hz


def cpu_seconds() -> float:
    """User + system time of this process and its reaped children."""
    usage = [resource.getrusage(who) for who in (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN)]
    return sum(u.ru_utime + u.ru_stime for u in usage)


def measure(run: Callable[[], None]) -> tuple[float, float]:
    """(wall seconds, CPU seconds) of one call."""
    wall, cpu = time.perf_counter(), cpu_seconds()
    run()
    return time.perf_counter() - wall, cpu_seconds() - cpu


def make_episodes(out: Path, episodes: int, steps: int, size, cameras) -> list[Path]:
    for index in range(episodes):
        path = out / f"synthetic_{index:03d}.rmb"
        with EpisodeWriter(path, ur5e_attrs(cameras), fk=UR5E) as writer:
            for step in ur5e_steps(steps, cameras, size, seed=index):
                writer.append(step)
    return find_episodes(out)


def decode_only(paths: list[Path], depth: bool) -> None:
    for path in paths:
        with open_episode(path) as ep:
            for key in ep:
                if K.is_depth_image_key(key) and not depth:
                    continue
                series = ep[key]
                for start in range(0, len(ep), 32):
                    np.asarray(series[start : start + 32])


def png_round_trip(paths: list[Path], root: Path, depth: bool) -> None:
    plan = plan_conversion(paths, ConvertOptions(depth=depth))
    schema = plan.schema
    dataset = LeRobotDataset.create(
        "bench/png",
        fps=LEROBOT_INT_FPS,
        features=schema.features(),
        root=root,
        robot_type=plan.robot_type,
        depth_encoder=quiet_depth_encoder(preset=None),  # x265's default, as LeRobot's
    )
    for source in plan.episodes:
        with open_episode(source.path) as ep:
            lowdim = {key: np.asarray(ep[key][:]) for key in schema.lowdim_keys}
            images = {f: np.asarray(ep[key][:]) for f, key in schema.image_keys().items()}
        arrays = schema.episode_arrays(lowdim, 1)
        for i in range(source.length):
            frame = {feature: values[i] for feature, values in arrays.items()}
            for feature, frames in images.items():
                frame[feature] = frames[i][..., None] if frames[i].ndim == 2 else frames[i]
            dataset.add_frame({**frame, "task": source.task})
        dataset.save_episode()
    dataset.finalize()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=2)
    parser.add_argument("--steps", type=int, default=100)
    parser.add_argument("--size", type=int, nargs=2, default=[640, 480], metavar=("W", "H"))
    parser.add_argument("--cameras", nargs="+", default=["front", "hand"])
    parser.add_argument("--workdir", type=Path, help="keep files here (default: a temp dir)")
    parser.add_argument(
        "--workers-row", action="store_true", help="also convert with --workers 2 (copy)"
    )
    parser.add_argument("--depth-only", action="store_true", help="only the RGB + depth rows")
    args = parser.parse_args()

    import av
    import datasets

    av.logging.set_libav_level(av.logging.ERROR)
    datasets.disable_progress_bars()
    work = Path(args.workdir or tempfile.mkdtemp(prefix="bench_convert_"))
    work.mkdir(parents=True, exist_ok=True)
    source = work / "episodes"
    if not source.exists():
        make_episodes(source, args.episodes, args.steps, tuple(args.size), tuple(args.cameras))
    paths = find_episodes(source)
    frames = 0
    for path in paths:
        with open_episode(path) as ep:
            frames += len(ep)
    print(
        f"{len(paths)} episodes, {frames} frames, {len(args.cameras)} cameras "
        f"{args.size[0]}x{args.size[1]}"
    )

    rows = []
    runs = [("ours (LeRobot's AV1)", None, 1), ("ours (--video-codec copy)", COPY, 1)]
    if args.workers_row:
        runs.append(("ours (copy, --workers 2)", COPY, 2))
    for depth in (True,) if args.depth_only else (False, True):
        streams = "RGB + depth" if depth else "RGB"
        decode = measure(lambda d=depth: decode_only(paths, d))
        results = {"decode only": decode}
        for name, codec, workers in runs:
            out = work / f"ours_{codec}_{workers}_{int(depth)}"
            shutil.rmtree(out, ignore_errors=True)
            options = ConvertOptions(depth=depth)
            results[name] = measure(
                lambda o=out, opt=options, c=codec, w=workers: to_lerobot(
                    [source], output=o, options=opt, video_codec=c, workers=w, progress=False
                )
            )
        png_root = work / f"png_{int(depth)}"
        shutil.rmtree(png_root, ignore_errors=True)
        png = results["PNG round trip (AV1)"] = measure(
            lambda r=png_root, d=depth: png_round_trip(paths, r, d)
        )
        for name, (wall, cpu) in results.items():
            speedup = f"{png[0] / wall:.2f}x / {png[1] / cpu:.2f}x"
            vs_decode = f"{wall / decode[0]:.1f}x / {cpu / decode[1]:.1f}x"
            rows.append((streams, name, frames / wall, 100 * cpu / frames, speedup, vs_decode))

    print(
        "\n| streams | converter | frames/s | CPU s / 100 frames "
        "| speed-up over PNG round trip (wall / CPU) | time vs decode only (wall / CPU) |"
    )
    print("|---|---|---:|---:|---:|---:|")
    for streams, name, rate, cpu, speedup, vs_decode in rows:
        print(f"| {streams} | {name} | {rate:.1f} | {cpu:.2f} | {speedup} | {vs_decode} |")
    if args.workdir is None:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
