"""Env steps per second with 0, 1 and 4 cameras, against raw ``mj_step`` on the same model.

Usage::

    .venv/bin/python benchmarks/env_step.py [--task insert] [--steps 20]
        [--visual-mesh-error 0.0005] [--no-antialias] [--repeats 3]

One env step is ``frame_skip`` (8) physics steps plus rendering of the requested cameras. The
"physics limit" is ``mj_step`` throughput of the same compiled model divided by ``frame_skip``,
measured in the same run; the last column is the env's share of it. "CPU ms/step" is the
process's CPU time per step (all threads, incl. llvmpipe's), which other jobs on the machine
barely change; wall-clock rates are the best of ``--repeats`` rounds. ``--visual-mesh-error 0``
renders the robot's original (full-detail) visual meshes; the default is the env's default
simplification. Env construction time is printed too (mesh cache warm after the first env).
"""

from __future__ import annotations

import argparse
import time

from rmb_lerobot.envs.base import RmbEnv
from rmb_lerobot.envs.mujoco.meshes import DEFAULT_VISUAL_MESH_ERROR
from rmb_lerobot.envs.mujoco.render import mujoco
from rmb_lerobot.envs.registry import ENVS

CAMERA_SETS = {0: (), 1: ("front",), 4: ("front", "left", "right", "hand")}
SIZES = ((128, 128), (640, 480))


def physics_steps_per_second(env: RmbEnv, seconds: float = 2.0) -> float:
    """Raw ``mj_step`` rate on the env's own model and state, holding the home command: the
    best of 0.25 s rounds over ``seconds``."""
    env.reset(seed=0)
    data = env.sim.data
    best, end = 0.0, time.perf_counter() + seconds
    while time.perf_counter() < end:
        steps, start = 0, time.perf_counter()
        while time.perf_counter() - start < 0.25:
            mujoco.mj_step(env.sim.model, data, nstep=100)
            steps += 100
        best = max(best, steps / (time.perf_counter() - start))
    return best


def env_steps_per_second(env: RmbEnv, steps: int, repeats: int = 1) -> tuple[float, float]:
    """Best wall-clock rate over ``repeats`` rounds of ``steps`` steps, and the least CPU time
    per step (ms, all threads of this process: the work, whatever else shares the CPU)."""
    env.reset(seed=0)
    action = env.home_command
    env.step(action)  # first render allocates buffers
    best, cpu_ms = 0.0, float("inf")
    for _ in range(repeats):
        start, cpu_start = time.perf_counter(), time.process_time()
        for _ in range(steps):
            env.step(action)
        best = max(best, steps / (time.perf_counter() - start))
        cpu_ms = min(cpu_ms, (time.process_time() - cpu_start) * 1e3 / steps)
    return best, cpu_ms


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", default="insert", choices=sorted(ENVS))
    parser.add_argument("--steps", type=int, default=20, help="env steps per configuration")
    parser.add_argument(
        "--visual-mesh-error",
        type=float,
        default=DEFAULT_VISUAL_MESH_ERROR,
        help="robot visual mesh simplification bound in metres (0: original meshes)",
    )
    parser.add_argument(
        "--no-antialias", action="store_true", help="render without 4x multisampling"
    )
    parser.add_argument(
        "--repeats", type=int, default=3, help="rounds per configuration; the best is reported"
    )
    args = parser.parse_args()
    options = {"visual_mesh_error": args.visual_mesh_error, "antialias": not args.no_antialias}

    entry = ENVS[args.task]
    start = time.perf_counter()
    base_env = entry.make(cameras=(), **options)
    construct_first = time.perf_counter() - start
    physics = physics_steps_per_second(base_env)
    limit = physics / base_env.sim.frame_skip
    rows = [("raw mj_step", "-", "-", (limit, float("nan")))]
    rows.append(
        ("0 cameras", "-", "-", env_steps_per_second(base_env, args.steps * 10, args.repeats))
    )
    base_env.close()
    for width, height in SIZES:
        for n_cams in (1, 4):
            for depth in (False, True):
                start = time.perf_counter()
                env = entry.make(
                    cameras=CAMERA_SETS[n_cams],
                    image_size=(width, height),
                    depth=depth,
                    **options,
                )
                construct_again = time.perf_counter() - start
                rate = env_steps_per_second(env, args.steps, args.repeats)
                env.close()
                label = f"{n_cams} camera{'s' if n_cams > 1 else ''}"
                rows.append((label, f"{width}x{height}", "RGB+D" if depth else "RGB", rate))

    print(
        f"task {args.task}: mj_step {physics:,.0f} steps/s; physics limit {limit:,.0f} env steps/s"
    )
    print(
        f"visual_mesh_error {args.visual_mesh_error:g} m, antialias {not args.no_antialias}; "
        f"env construction {construct_first:.2f} s first, {construct_again:.2f} s last"
    )
    print(
        f"| {'config':<12} | {'size':<8} | {'images':<6} | {'env steps/s':>11} | "
        f"{'ms/step':>8} | {'CPU ms/step':>11} | {'of limit':>8} |"
    )
    print(f"|{'-' * 14}|{'-' * 10}|{'-' * 8}|{'-' * 13}|{'-' * 10}|{'-' * 13}|{'-' * 10}|")
    for label, size, images, (rate, cpu_ms) in rows:
        print(
            f"| {label:<12} | {size:<8} | {images:<6} | {rate:>11.1f} | {1e3 / rate:>8.2f} | "
            f"{cpu_ms:>11.2f} | {rate / limit:>8.1%} |"
        )


if __name__ == "__main__":
    main()
