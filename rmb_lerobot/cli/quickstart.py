"""``rmb-quickstart``: the main job of the README, end to end on this machine.

Today it records a synthetic UR5e episode in both RMB variants (streaming writer, derived eef
poses and ``_rel`` keys), reads both back by random access, checks them against each other and
against ``switch-format``, and prints a summary. (The simulated environments, the LeRobot
conversion, training and evaluation join this pipeline as they land.)
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
from rmb_lerobot.episode import EpisodeWriter, open_episode, switch_format
from rmb_lerobot.kinematics import UR5E
from rmb_lerobot.synthetic import ur5e_attrs, ur5e_steps


def _size_mb(path: Path) -> float:
    files = [path] if path.is_file() else [p for p in path.rglob("*") if p.is_file()]
    return sum(p.stat().st_size for p in files) / 1e6


def _psnr(a: np.ndarray, b: np.ndarray) -> float:
    mse = np.mean((a.astype(np.float64) - b.astype(np.float64)) ** 2)
    return float("inf") if mse == 0 else 10 * np.log10(255**2 / mse)


def record(path: Path, steps: int, cameras: tuple[str, ...], size: tuple[int, int]) -> float:
    """Write one synthetic episode; returns the seconds it took."""
    start = time.perf_counter()
    with EpisodeWriter(path, ur5e_attrs(cameras), fk=UR5E, overwrite=True) as writer:
        for step in tqdm(ur5e_steps(steps, cameras, size), total=steps, desc=f"record {path.name}"):
            writer.append(step)
    return time.perf_counter() - start


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
    parser.add_argument("--steps", type=int, default=150)
    parser.add_argument("--cameras", nargs="+", default=["front", "hand"])
    parser.add_argument("--image-size", nargs=2, type=int, default=[640, 480], metavar=("W", "H"))
    args = parser.parse_args(argv)

    out: Path = args.out
    if out.exists():
        shutil.rmtree(out)
    out.mkdir(parents=True)
    cameras, size = tuple(args.cameras), tuple(args.image_size)

    compact, single = out / "synthetic_ur5e.rmb", out / "synthetic_ur5e.hdf5"
    report = []
    for path in (compact, single):
        seconds = record(path, args.steps, cameras, size)
        report.append(f"recorded {path.name}: {args.steps} steps in {seconds:.1f} s")
    switched = switch_format(compact, out / "switched_from_rmb.hdf5")
    report += summarize(compact) + summarize(single)
    report += compare(single, compact) + compare(compact, switched)
    key = K.depth_image_key(cameras[0])
    report.append(f"random-access read of one {key} frame: {random_access_ms(compact, key):.1f} ms")
    print("\n".join(report))
    print(f"\nOK: episodes in {out.resolve()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
