"""The training data path: LeRobot's loader on a full conversion vs ``--no-extra-keys``.

Usage::

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/lean_dataset.py [--episodes 10] [--steps 50]
        [--size 64 64] [--samples 400]

Data: synthetic UR5e episodes (:mod:`rmb_lerobot.synthetic`) shaped as the quick start's (two
cameras at 64x64, no depth, ~50 steps), converted twice with ``rmb-convert to-lerobot``: with
every RMB key as its own feature (the default) and with ``--no-extra-keys`` (only
``observation.state``, ``action`` and the cameras). One sample is what the quick start's ACT
asks for: state and both images at t, actions t .. t+19. The loader reads every column of each
row it touches, so the extra columns cost time on every sample although no policy reads them.
Both datasets must give identical samples (checked here, and in
``tests/converters/test_to_lerobot.py``).
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np
import torch
from lerobot.datasets.lerobot_dataset import LeRobotDataset

from rmb_lerobot import EpisodeWriter
from rmb_lerobot import lerobot_names as N
from rmb_lerobot.converters import ConvertOptions, to_lerobot
from rmb_lerobot.kinematics import UR5E
from rmb_lerobot.synthetic import UR5E_CONTROL_HZ, ur5e_attrs, ur5e_steps

CAMERAS = ("front", "hand")
CHUNK = 20  # the quick start's ACT chunk_size


def make_data(work: Path, episodes: int, steps: int, size: tuple[int, int]) -> dict[bool, Path]:
    """Episodes, then the full (True) and lean (False) conversions."""
    source = work / "episodes"
    for index in range(episodes):
        with EpisodeWriter(
            source / f"synthetic_{index:03d}.rmb", ur5e_attrs(CAMERAS), fk=UR5E
        ) as w:
            for step in ur5e_steps(steps, CAMERAS, size, seed=index):
                w.append(step)
    roots = {}
    for extra in (True, False):
        roots[extra] = work / ("full" if extra else "lean")
        to_lerobot([source], output=roots[extra], options=ConvertOptions(extra_keys=extra))
    return roots


def loader(root: Path):
    """A sampler of what ACT asks for, and the dataset's length and column count."""
    delta = {N.ACTION_KEY: [i / UR5E_CONTROL_HZ for i in range(CHUNK)]}
    dataset = LeRobotDataset(
        f"local/{root.name}", root=root, delta_timestamps=delta, video_backend="pyav"
    )
    keys = [N.STATE, N.ACTION_KEY, *(N.image_key(c) for c in CAMERAS)]

    def sample(index: int) -> dict[str, torch.Tensor]:
        item = dataset[index]
        return {key: item[key] for key in keys}

    return sample, len(dataset), len(dataset.hf_dataset.column_names)


def disk_mb(root: Path) -> float:
    return sum(p.stat().st_size for p in root.rglob("*") if p.is_file()) / 1e6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=10)
    parser.add_argument("--steps", type=int, default=50)
    parser.add_argument("--size", type=int, nargs=2, default=[64, 64], metavar=("W", "H"))
    parser.add_argument("--samples", type=int, default=400)
    parser.add_argument("--repeats", type=int, default=3, help="alternating rounds; median kept")
    args = parser.parse_args()
    import datasets

    datasets.disable_progress_bars()
    work = Path(tempfile.mkdtemp(prefix="bench_lean_"))
    try:
        roots = make_data(work, args.episodes, args.steps, tuple(args.size))
        samplers = {extra: loader(root) for extra, root in roots.items()}
        count = samplers[True][1]
        indices = np.random.default_rng(0).integers(0, count, args.samples)
        for index in indices[:50]:  # same samples, same tensors
            full, lean = samplers[True][0](int(index)), samplers[False][0](int(index))
            assert all(torch.equal(full[k], lean[k]) for k in full), f"sample {index} differs"
        cpu: dict[bool, list[float]] = {True: [], False: []}
        for _ in range(args.repeats):  # alternate, so load changes hit both alike
            for extra in (True, False):
                sample = samplers[extra][0]
                start = time.process_time()
                for index in indices:
                    sample(int(index))
                cpu[extra].append(1000 * (time.process_time() - start) / args.samples)
        print(
            f"{args.episodes} episodes x {args.steps} steps, cameras {CAMERAS} at "
            f"{args.size[0]}x{args.size[1]}, {args.samples} samples x {args.repeats} rounds; "
            "samples identical: yes"
        )
        print("\n| dataset | columns | disk MB | CPU ms/sample (median) | ratio |")
        print("|---|---:|---:|---:|---:|")
        base = float(np.median(cpu[True]))
        for extra, name in ((True, "full (default)"), (False, "--no-extra-keys")):
            ms = float(np.median(cpu[extra]))
            columns = samplers[extra][2]
            print(
                f"| {name} | {columns} | {disk_mb(roots[extra]):.2f} | {ms:.2f} | {ms / base:.2f} |"
            )
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
