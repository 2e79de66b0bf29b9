"""``rmb-data verify`` against ``rmb-convert to-lerobot`` on the same episode, in one run.

Usage::

    .venv/bin/python benchmarks/verify.py [--steps 300] [--size 640 480]
        [--cameras front hand left right] [--workdir DIR]

Source: one synthetic UR5e episode (:mod:`rmb_lerobot.synthetic`, RGB + depth per camera)
written as a compact ``.rmb`` episode by our writer (checksummed HDF5, H.264 RGB, lossless
``rmb-videoio`` depth, digests). Rows: ``verify`` of the episode (every dataset read, every
frame of the 2 x cameras videos decoded, every digest checked); ``to-lerobot --depth`` of the
same episode with LeRobot's default AV1 (what verify must be well under); ``verify`` of the
converted dataset. Wall clock and CPU seconds (this process and its children).
"""

from __future__ import annotations

import argparse
import resource
import shutil
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from rmb_lerobot import EpisodeWriter
from rmb_lerobot.converters import ConvertOptions, to_lerobot
from rmb_lerobot.data.verify import format_table, verify_paths
from rmb_lerobot.kinematics import UR5E
from rmb_lerobot.synthetic import ur5e_attrs, ur5e_steps


def cpu_seconds() -> float:
    """User + system time of this process and its reaped children."""
    usage = [resource.getrusage(who) for who in (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN)]
    return sum(u.ru_utime + u.ru_stime for u in usage)


def measure(run: Callable[[], object]) -> tuple[float, float]:
    """(wall s, CPU s) of one call."""
    wall, cpu = time.perf_counter(), cpu_seconds()
    run()
    return time.perf_counter() - wall, cpu_seconds() - cpu


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=300, help="episode length")
    parser.add_argument("--size", type=int, nargs=2, default=(640, 480), metavar=("W", "H"))
    parser.add_argument("--cameras", nargs="+", default=["front", "hand", "left", "right"])
    parser.add_argument("--workdir", type=Path, help="keep files here (default: a temp dir)")
    args = parser.parse_args()
    work = args.workdir or Path(tempfile.mkdtemp(prefix="bench-verify-"))
    work.mkdir(parents=True, exist_ok=True)
    cameras = tuple(args.cameras)
    episode = work / "episode.rmb"
    if not episode.exists():
        with EpisodeWriter(episode, ur5e_attrs(cameras), fk=UR5E) as writer:
            for step in ur5e_steps(args.steps, cameras, tuple(args.size), seed=0):
                writer.append(step)
    dataset = work / "dataset"
    shutil.rmtree(dataset, ignore_errors=True)

    verify_ep = measure(lambda: verify_paths([episode], progress=False))
    convert = measure(
        lambda: to_lerobot(
            [episode], output=dataset, options=ConvertOptions(depth=True), progress=False
        )
    )
    verify_ds = measure(lambda: verify_paths([dataset], progress=False))
    print(format_table(verify_paths([episode, dataset], progress=False)))
    frames = args.steps * len(cameras)
    print(f"\n{args.steps} steps, {len(cameras)} cameras {args.size[0]}x{args.size[1]} (RGB+depth)")
    print("| run | wall s | CPU s | wall vs conversion |")
    print("|---|---|---|---|")
    for name, (wall, cpu) in (
        ("rmb-data verify episode.rmb", verify_ep),
        ("rmb-convert to-lerobot --depth (LeRobot's AV1)", convert),
        ("rmb-data verify of the converted dataset", verify_ds),
    ):
        print(f"| {name} | {wall:.1f} | {cpu:.1f} | {wall / convert[0]:.2f} |")
    print(f"verify/convert wall ratio: {verify_ep[0] / convert[0]:.3f} ({frames} camera frames)")


if __name__ == "__main__":
    main()
