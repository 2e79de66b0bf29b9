"""Control-loop timing of the real env at 50 Hz on the UR5e twin, with 0, 1 and 2 cameras.

For each camera count, a real env (``RealUR5eDemo``, ``driver: sim``) runs ``--steps`` steps of
a small joint sine through :class:`~rmb_lerobot.envs.base.RmbEnv` (safety layer, twin's SDK
calls, the Robotiq socket, camera frames with depth, observations), and reports:

- period error: ``|t[k+1] - t[k] - 0.02|`` between consecutive ticks (the arms' reading at the
  end of each period), p50 / p99 / max in ms, and the overruns (a step that reached its tick
  late; the loop then restarts its schedule);
- command latency: from the observation's reading to the command being handed to the arm
  (env, policy and safety layer together), p50 / p99 in ms.

The baseline, measured in the same run, is the same sleep-and-spin pacing with no robot: the
machine's own scheduling noise. Twin cameras render in their own threads (software GL on a
machine without a GPU), as a RealSense captures in its own.

With ``--realtime-priority N`` the loop's thread runs under ``SCHED_FIFO`` (the env option
``realtime_priority``; the baseline too, so the two stay comparable); without it, under the
normal scheduler.

    OMP_NUM_THREADS=1 MUJOCO_GL=egl .venv/bin/python benchmarks/real_loop.py --steps 500
    OMP_NUM_THREADS=1 MUJOCO_GL=egl .venv/bin/python benchmarks/real_loop.py --steps 500 \
        --realtime-priority 70
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from rmb_lerobot.envs.real.cameras import TwinCameraConfig
from rmb_lerobot.envs.real.config import make_real_env
from rmb_lerobot.envs.real.realtime import use_realtime_priority

PERIOD = 0.02
WATCHDOG_TIMEOUT = 2.0  # s (default 0.2 s): see run()


def baseline(steps: int, spin_s: float) -> np.ndarray:
    """Periods (s) of the backend's pacing alone: sleep to ``spin_s`` before each tick, spin."""
    ticks = [time.monotonic()]
    tick = ticks[0] + PERIOD
    for _ in range(steps):
        now = time.monotonic()
        if tick - now > spin_s:
            time.sleep(tick - now - spin_s)
        while (now := time.monotonic()) < tick:
            pass
        ticks.append(now)
        tick = max(tick + PERIOD, now)
    return np.diff(ticks)


def run(
    cameras: int, steps: int, size: tuple[int, int], priority: int | None, spin_s: float
) -> dict[str, float]:
    """One camera count: the env's tick periods and command latencies."""
    width, height = size
    views = [("front", "front"), ("hand", "hand")][:cameras]
    configs = {
        name: TwinCameraConfig(view=view, width=width, height=height, use_depth=True)
        for name, view in views
    }
    env = make_real_env(
        "RealUR5eDemo",
        {
            "driver": "sim",
            "camera_configs": configs,
            "image_size": size,
            # A loaded machine stalls the loop now and then; the run measures it rather than
            # stopping at the first stall longer than the default 0.2 s.
            "watchdog_timeout": WATCHDOG_TIMEOUT,
            "realtime_priority": priority,
            "spin_s": spin_s,
        },
    )
    try:
        env.reset(seed=0)
        home = env.home_command
        for k in range(steps):
            action = home.copy()
            action[0] += 0.1 * np.sin(2 * np.pi * k * PERIOD / 4.0)
            env.step(action)
        timing = env.sim.timing
        periods, latencies = timing.periods(), np.asarray(timing.latencies)
        return summary(periods) | {
            "overruns": timing.overruns,
            "lat_p50": 1e3 * float(np.percentile(latencies, 50)),
            "lat_p99": 1e3 * float(np.percentile(latencies, 99)),
        }
    finally:
        env.close()


def summary(periods: np.ndarray) -> dict[str, float]:
    """p50 / p99 / max of the period error in ms."""
    error = 1e3 * np.abs(periods - PERIOD)
    return {
        "p50": float(np.percentile(error, 50)),
        "p99": float(np.percentile(error, 99)),
        "max": float(error.max()),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=500, help="steps per run (50 per second)")
    parser.add_argument("--size", type=int, nargs=2, default=(128, 128), metavar=("W", "H"))
    parser.add_argument("--cameras", type=int, nargs="+", default=(0, 1, 2))
    parser.add_argument(
        "--realtime-priority", type=int, default=None, help="SCHED_FIFO priority of the loop"
    )
    parser.add_argument(
        "--spin-s", type=float, default=0.001, help="spin before each tick (s; env option)"
    )
    args = parser.parse_args()
    print(f"load average before: {os.getloadavg()}, cores: {os.cpu_count()}")
    fifo = args.realtime_priority
    print(f"scheduling: {'normal' if fifo is None else f'SCHED_FIFO {fifo}'}")
    previous = None
    if args.realtime_priority is not None:
        previous = use_realtime_priority(args.realtime_priority)
    base = summary(baseline(args.steps, args.spin_s))
    if previous is not None:
        previous.restore()  # each env takes the priority itself from its first reset
    rows = [("baseline (pacing only)", base | {"overruns": 0, "lat_p50": 0.0, "lat_p99": 0.0})]
    for n in args.cameras:
        rows.append(
            (
                f"{n} camera(s) {args.size[0]}x{args.size[1]}",
                run(n, args.steps, args.size, args.realtime_priority, args.spin_s),
            )
        )
    print(f"load average after: {os.getloadavg()}")
    print(
        "| loop | period error p50 (ms) | p99 (ms) | max (ms) | p99 / baseline p99 | overruns "
        "| latency p50 (ms) | p99 (ms) |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    for name, r in rows:
        ratio = r["p99"] / base["p99"] if base["p99"] > 0 else float("inf")
        print(
            f"| {name} | {r['p50']:.3f} | {r['p99']:.3f} | {r['max']:.2f} | {ratio:.1f} | "
            f"{r['overruns']} | {r['lat_p50']:.2f} | {r['lat_p99']:.2f} |"
        )


if __name__ == "__main__":
    main()
