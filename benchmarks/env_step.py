"""Env steps per second with and without cameras (and tactile images), against the raw physics
step of the same world.

Usage::

    .venv/bin/python benchmarks/env_step.py [--task insert] [--steps 20]
        [--visual-mesh-error 0.0005] [--no-antialias] [--repeats 3]
    .venv/bin/python benchmarks/env_step.py --task pybullet_sawyer_grasp [--renderer egl]

MuJoCo: one env step is ``frame_skip`` (8) physics steps plus rendering of the requested cameras
(0, 1 or 4); the "physics limit" is ``mj_step`` throughput of the same compiled model divided by
``frame_skip``. PyBullet (RMB's TACTO envs): one env step is 6 ``stepSimulation`` substeps plus
the front camera and/or the two fingertip tactile images; the limit is ``stepSimulation``
throughput of the same world divided by 6. Both are measured in the same run; the last column
is the env's share of the limit. "CPU ms/step" is the
process's CPU time per step (all threads, incl. llvmpipe's), which other jobs on the machine
barely change; wall-clock rates are the best of ``--repeats`` rounds. ``--visual-mesh-error 0``
renders the robot's original (full-detail) visual meshes; the default is the env's default
simplification. Env construction time is printed too (mesh cache warm after the first env).
"""

from __future__ import annotations

import argparse
import time

from rmb_lerobot.envs.base import RmbEnv
from rmb_lerobot.envs.mujoco.options import DEFAULT_VISUAL_MESH_ERROR
from rmb_lerobot.envs.registry import ENVS

CAMERA_SETS = {0: (), 1: ("front",), 4: ("front", "left", "right", "hand")}
SIZES = ((128, 128), (640, 480))


def _best_rate(step_100, seconds: float) -> float:
    """Best rate of ``step_100()`` (100 steps a call) over 0.25 s rounds for ``seconds``."""
    best, end = 0.0, time.perf_counter() + seconds
    while time.perf_counter() < end:
        steps, start = 0, time.perf_counter()
        while time.perf_counter() - start < 0.25:
            step_100()
            steps += 100
        best = max(best, steps / (time.perf_counter() - start))
    return best


def physics_steps_per_second(env: RmbEnv, seconds: float = 2.0) -> tuple[float, int]:
    """Raw physics step rate on the env's own world and state, holding the home command, and
    the physics steps per env step: ``mj_step`` and ``frame_skip`` for MuJoCo,
    ``stepSimulation`` and its 6 substeps for PyBullet."""
    env.reset(seed=0)
    sim = env.sim
    if env.simulator == "pybullet":
        import pybullet as p

        def step_100() -> None:
            for _ in range(100):
                p.stepSimulation(physicsClientId=sim.client_id)

        return _best_rate(step_100, seconds), round(env.control_dt / 0.005)
    from rmb_lerobot.envs.mujoco.render import mujoco

    return _best_rate(lambda: mujoco.mj_step(sim.model, sim.data, nstep=100), seconds), (
        sim.frame_skip
    )


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


def _configurations(
    simulator: str, env_cameras: tuple[str, ...] = CAMERA_SETS[4]
) -> list[tuple[str, tuple[str, ...], tuple[int, int], bool]]:
    """``(label, cameras, image size, depth)`` rows measured for a simulator: MuJoCo envs with
    ``front`` (or the first of ``env_cameras`` in a scene without one: ALOHA's overhead_cam)
    alone and with all ``env_cameras`` (the env's own: a robot without a hand camera has three,
    a dual arm six)."""
    if simulator == "pybullet":
        tactile = ("tactile_left", "tactile_right")
        rows = []
        for size in SIZES:
            rows.append(("front", ("front",), size, False))
            rows.append(("front", ("front",), size, True))
            rows.append(("2 tactile", tactile, size, False))
            rows.append(("front+tactile", ("front", *tactile), size, True))
        return rows
    sets = (tuple(env_cameras[:1]), tuple(env_cameras))  # its first: front, where there is one
    return [
        (f"{len(cameras)} camera{'s' if len(cameras) > 1 else ''}", cameras, size, depth)
        for size in SIZES
        for cameras in sets
        for depth in (False, True)
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", default="insert", choices=sorted(ENVS))
    parser.add_argument("--steps", type=int, default=20, help="env steps per configuration")
    parser.add_argument(
        "--visual-mesh-error",
        type=float,
        default=DEFAULT_VISUAL_MESH_ERROR,
        help="MuJoCo: robot visual mesh simplification bound in metres (0: original meshes)",
    )
    parser.add_argument(
        "--no-antialias", action="store_true", help="MuJoCo: render without 4x multisampling"
    )
    parser.add_argument(
        "--renderer", default="auto", help="PyBullet: egl, tiny or auto (EGL, else tiny)"
    )
    parser.add_argument(
        "--repeats", type=int, default=3, help="rounds per configuration; the best is reported"
    )
    args = parser.parse_args()
    entry = ENVS[args.task]
    if entry.simulator == "pybullet":
        options = {"renderer": args.renderer}
        described = f"renderer {args.renderer}"
    else:
        options = {"visual_mesh_error": args.visual_mesh_error, "antialias": not args.no_antialias}
        described = (
            f"visual_mesh_error {args.visual_mesh_error:g} m, antialias {not args.no_antialias}"
        )

    start = time.perf_counter()
    base_env = entry.make(cameras=(), **options)
    construct_first = time.perf_counter() - start
    physics, substeps = physics_steps_per_second(base_env)
    limit = physics / substeps
    rows = [("raw physics", "-", "-", (limit, float("nan")))]
    rows.append(
        ("0 cameras", "-", "-", env_steps_per_second(base_env, args.steps * 10, args.repeats))
    )
    base_env.close()
    for label, cameras, (width, height), depth in _configurations(entry.simulator, entry.cameras):
        start = time.perf_counter()
        env = entry.make(cameras=cameras, image_size=(width, height), depth=depth, **options)
        construct_again = time.perf_counter() - start
        rate = env_steps_per_second(env, args.steps, args.repeats)
        env.close()
        rows.append((label, f"{width}x{height}", "RGB+D" if depth else "RGB", rate))

    print(
        f"task {args.task}: physics {physics:,.0f} steps/s; {substeps} per env step; physics "
        f"limit {limit:,.0f} env steps/s"
    )
    print(
        f"{described}; env construction {construct_first:.2f} s first, {construct_again:.2f} s last"
    )
    print(
        f"| {'config':<13} | {'size':<8} | {'images':<6} | {'env steps/s':>11} | "
        f"{'ms/step':>8} | {'CPU ms/step':>11} | {'of limit':>8} |"
    )
    print(f"|{'-' * 15}|{'-' * 10}|{'-' * 8}|{'-' * 13}|{'-' * 10}|{'-' * 13}|{'-' * 10}|")
    for label, size, images, (rate, cpu_ms) in rows:
        print(
            f"| {label:<13} | {size:<8} | {images:<6} | {rate:>11.1f} | {1e3 / rate:>8.2f} | "
            f"{cpu_ms:>11.2f} | {rate / limit:>8.1%} |"
        )


if __name__ == "__main__":
    main()
