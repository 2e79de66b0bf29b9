"""``rmb-quickstart``: the main job of the README, end to end on this machine.

It collects scripted-expert demonstrations in an RMB simulation env (``rmb-collect``), reads
the episodes back by random access, switches one to the single-file variant and checks both
against each other, and prints a summary. (Conversion to LeRobotDataset, training and
evaluation join this pipeline as they land.)
"""

from __future__ import annotations

import argparse
import shutil
import sys
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from tqdm import tqdm

from rmb_lerobot import keys as K
from rmb_lerobot.episode import open_episode, switch_format


def _size_mb(path: Path) -> float:
    files = [path] if path.is_file() else [p for p in path.rglob("*") if p.is_file()]
    return sum(p.stat().st_size for p in files) / 1e6


def _psnr(a: np.ndarray, b: np.ndarray) -> float:
    mse = np.mean((a.astype(np.float64) - b.astype(np.float64)) ** 2)
    return float("inf") if mse == 0 else 10 * np.log10(255**2 / mse)


def collect_demos(env: str, out: Path, episodes: int, cameras, size, workers: int) -> list[Path]:
    """Record scripted demonstrations (the ``rmb-collect`` pipeline); returns episode paths."""
    from rmb_lerobot.envs.collect import CollectConfig, collect

    config = CollectConfig(env, out, episodes, cameras=tuple(cameras), image_size=tuple(size))
    paths, successes = [], 0
    for result in tqdm(collect(config, workers), total=episodes, desc=f"collect {env}"):
        successes += result.success
        if result.path is not None:
            paths.append(result.path)
    print(f"collected {len(paths)} episodes of {env}, {successes} successful")
    return sorted(paths)


def summarize(path: Path) -> list[str]:
    lines = [f"{path}  ({_size_mb(path):.2f} MB)"]
    with open_episode(path) as ep:
        lines.append(
            f"  format={ep.format.value} steps={len(ep)} fps={ep.fps:.2f} cameras={ep.camera_names}"
        )
        for key in ep:
            series = ep[key]
            sample = series[0]
            lines.append(f"  {key:32s} {tuple(series.shape)!s:22s} {sample.dtype}")
        for name, value in sorted(ep.attrs.items()):
            lines.append(f"  @{name} = {value!r}")
    return lines


def compare(a: Path, b: Path) -> list[str]:
    """How far two recordings of the same episode are apart, key by key."""
    lines = [f"{a.name} vs {b.name}"]
    with open_episode(a) as ea, open_episode(b) as eb:
        for key in ea:
            x, y = np.asarray(ea[key][:]), np.asarray(eb[key][:])
            if K.is_rgb_image_key(key):
                lines.append(f"  {key:32s} PSNR {_psnr(x, y):.1f} dB")
            elif K.is_depth_image_key(key):
                err = np.abs(x.astype(np.float64) - y) * 1000
                lines.append(f"  {key:32s} max |error| {err.max():.2f} mm")
            elif not np.array_equal(x, y):
                raise SystemExit(f"low-dimensional key {key!r} differs between {a} and {b}")
        lines.append("  low-dimensional keys and attributes: identical")
    return lines


def random_access_ms(path: Path, key: str, reads: int = 10) -> float:
    rng = np.random.default_rng(0)
    with open_episode(path) as ep:
        series = ep[key]
        start = time.perf_counter()
        for i in rng.integers(0, len(ep), reads):
            series[int(i)]
        return (time.perf_counter() - start) / reads * 1000


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="rmb-quickstart", description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("outputs/quickstart"))
    parser.add_argument("--env", default="MujocoUR5eInsert")
    parser.add_argument("--episodes", type=int, default=4)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--cameras", nargs="+", default=["front", "hand"])
    parser.add_argument("--image-size", nargs=2, type=int, default=[128, 128], metavar=("W", "H"))
    args = parser.parse_args(argv)

    out: Path = args.out
    if out.exists():
        shutil.rmtree(out)
    start = time.perf_counter()
    episodes = collect_demos(
        args.env, out / "rmb", args.episodes, args.cameras, args.image_size, args.workers
    )
    if not episodes:
        print("no episodes were collected", file=sys.stderr)
        return 1
    first = episodes[0]
    switched = switch_format(first, out / "switched" / f"{first.stem}.hdf5")
    report = summarize(first) + compare(first, switched)
    key = K.depth_image_key(args.cameras[0])
    report.append(f"random-access read of one {key} frame: {random_access_ms(first, key):.1f} ms")
    print("\n".join(report))
    print(f"\nOK in {time.perf_counter() - start:.0f} s: episodes in {(out / 'rmb').resolve()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
