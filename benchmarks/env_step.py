"""Env steps per second with 0, 1 and 4 cameras, against raw ``mj_step`` on the same model.

Usage::

    .venv/bin/python benchmarks/env_step.py [--task insert] [--steps 20]

One env step is ``frame_skip`` (8) physics steps plus rendering of the requested cameras. The
"physics limit" is ``mj_step`` throughput of the same compiled model divided by ``frame_skip``,
measured in the same run; the last column is the env's share of it.
"""

from __future__ import annotations

import argparse
import time

from rmb_lerobot.envs.base import RmbEnv
from rmb_lerobot.envs.catalog import TASKS
from rmb_lerobot.envs.mujoco.render import mujoco

CAMERA_SETS = {0: (), 1: ("front",), 4: ("front", "left", "right", "hand")}
SIZES = ((128, 128), (640, 480))


def physics_steps_per_second(env: RmbEnv, seconds: float = 2.0) -> float:
    """Raw ``mj_step`` rate on the env's own model and state, holding the home command."""
    env.reset(seed=0)
    data = env.data
    steps, start = 0, time.perf_counter()
    while time.perf_counter() - start < seconds:
        mujoco.mj_step(env.model, data, nstep=100)
        steps += 100
    return steps / (time.perf_counter() - start)


def env_steps_per_second(env: RmbEnv, steps: int) -> float:
    env.reset(seed=0)
    action = env.home_command
    env.step(action)  # first render allocates buffers
    start = time.perf_counter()
    for _ in range(steps):
        env.step(action)
    return steps / (time.perf_counter() - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", default="insert", choices=sorted(TASKS))
    parser.add_argument("--steps", type=int, default=20, help="env steps per configuration")
    args = parser.parse_args()

    task = TASKS[args.task]()
    base_env = RmbEnv(task, cameras=())
    physics = physics_steps_per_second(base_env)
    limit = physics / base_env.frame_skip
    rows = [("raw mj_step", "-", "-", physics / base_env.frame_skip)]
    rows.append(("0 cameras", "-", "-", env_steps_per_second(base_env, args.steps * 10)))
    base_env.close()
    for width, height in SIZES:
        for n_cams in (1, 4):
            for depth in (False, True):
                env = RmbEnv(
                    task, cameras=CAMERA_SETS[n_cams], image_size=(width, height), depth=depth
                )
                rate = env_steps_per_second(env, args.steps)
                env.close()
                label = f"{n_cams} camera{'s' if n_cams > 1 else ''}"
                rows.append((label, f"{width}x{height}", "RGB+D" if depth else "RGB", rate))

    print(
        f"task {args.task}: mj_step {physics:,.0f} steps/s; physics limit {limit:,.0f} env steps/s"
    )
    print(
        f"| {'config':<12} | {'size':<8} | {'images':<6} | {'env steps/s':>11} | "
        f"{'ms/step':>8} | {'of limit':>8} |"
    )
    print(f"|{'-' * 14}|{'-' * 10}|{'-' * 8}|{'-' * 13}|{'-' * 10}|{'-' * 10}|")
    for label, size, images, rate in rows:
        print(
            f"| {label:<12} | {size:<8} | {images:<6} | {rate:>11.1f} | {1e3 / rate:>8.2f} | "
            f"{rate / limit:>8.1%} |"
        )


if __name__ == "__main__":
    main()
