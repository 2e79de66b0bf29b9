"""A rendered step's per-pixel work: the old float64 millimetre conversion against the float32 one.

Usage::

    .venv/bin/python benchmarks/render_depth.py [--task insert] [--steps 10] [--repeats 7]
        [--size 640 480]

One env (4 cameras, RGB + depth, the given size) steps the same home command in alternating
rounds: "float64" with the conversion the env used before issue 27 (depth metres -> float64,
``rint``, ``isfinite``/range masks, ``where``, cast; copied here as the baseline), "float32"
with :func:`rmb_lerobot.codecs.depth_base.metres_to_mm` as it is now. Every round also checks
that both give the same uint16 millimetres. Then the same for an env with ``antialias=False``
(the documented fast path), whose images differ (no multisampling). Reported: median wall and
CPU (all threads, llvmpipe's included) ms per step over the rounds, the wall ms per step
spent in the conversion itself (4 cameras), and ratios to the first row; the
alternating rounds make the ratio fair on a machine shared with other jobs.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

import rmb_lerobot.envs.base as env_base
from rmb_lerobot.codecs.depth_base import MAX_DEPTH_MM
from rmb_lerobot.envs.registry import ENVS

CAMERAS = ("front", "left", "right", "hand")


def float64_metres_to_mm(depth_m: np.ndarray) -> np.ndarray:
    """The conversion before issue 27 (the baseline): all arithmetic on float64 images."""
    mm = np.rint(np.asarray(depth_m, dtype=np.float64) * 1000.0)
    valid = np.isfinite(mm) & (mm >= 0) & (mm <= MAX_DEPTH_MM)
    return np.where(valid, mm, 0).astype(np.uint16)


def timed_round(env, action: np.ndarray, steps: int, convert) -> tuple[float, float, float]:
    """Wall and CPU milliseconds per step over ``steps`` steps, and the wall milliseconds per
    step spent in the millimetre conversion ``convert`` (all cameras)."""
    spent = [0.0]

    def timed_convert(depth_m: np.ndarray) -> np.ndarray:
        start = time.perf_counter()
        try:
            return convert(depth_m)
        finally:
            spent[0] += time.perf_counter() - start

    env_base.metres_to_mm = timed_convert
    start, cpu = time.perf_counter(), time.process_time()
    for _ in range(steps):
        env.step(action)
    return (
        (time.perf_counter() - start) * 1e3 / steps,
        (time.process_time() - cpu) * 1e3 / steps,
        spent[0] * 1e3 / steps,
    )


def compare(env, steps: int, repeats: int) -> dict[str, list[tuple[float, float, float]]]:
    """Alternating old/new rounds on one env; asserts both conversions agree on its depth."""
    new = env_base.metres_to_mm
    env.reset(seed=0)
    action = env.home_command
    env.step(action)
    for depth_m in env._depth_m.values():
        if not np.array_equal(new(depth_m), float64_metres_to_mm(depth_m)):
            raise AssertionError("float32 and float64 millimetres differ")
    rounds: dict[str, list[tuple[float, float, float]]] = {"float64": [], "float32": []}
    try:
        for _ in range(repeats):
            for name, function in (("float64", float64_metres_to_mm), ("float32", new)):
                rounds[name].append(timed_round(env, action, steps, function))
    finally:
        env_base.metres_to_mm = new
    return rounds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", default="insert", choices=sorted(ENVS))
    parser.add_argument("--steps", type=int, default=10, help="env steps per round")
    parser.add_argument("--repeats", type=int, default=7, help="rounds per conversion")
    parser.add_argument("--size", type=int, nargs=2, default=(640, 480), metavar=("W", "H"))
    args = parser.parse_args()
    print(
        f"task {args.task}, cameras {', '.join(CAMERAS)}, {args.size[0]}x{args.size[1]} RGB + "
        f"depth, {args.steps} steps x {args.repeats} rounds each, medians"
    )
    print(
        "| antialias | conversion | wall ms/step | CPU ms/step | conversion ms/step | "
        "wall ratio | CPU ratio | conversion ratio |"
    )
    print("|---|---|---:|---:|---:|---:|---:|---:|")
    base = None
    for antialias in (True, False):
        env = ENVS[args.task].make(
            cameras=CAMERAS, image_size=tuple(args.size), depth=True, antialias=antialias
        )
        try:
            rounds = compare(env, args.steps, args.repeats)
        finally:
            env.close()
        for name, values in rounds.items():
            wall = statistics.median(v[0] for v in values)
            cpu = statistics.median(v[1] for v in values)
            convert = statistics.median(v[2] for v in values)
            base = base or (wall, cpu, convert)
            print(
                f"| {antialias} | {name} | {wall:.1f} | {cpu:.1f} | {convert:.2f} | "
                f"{wall / base[0]:.2f} | {cpu / base[1]:.2f} | {convert / base[2]:.2f} |"
            )


if __name__ == "__main__":
    main()
