"""Rate of the ``rmb-teleop`` loop: MuJoCo at 31.25 Hz with a 640x480 camera and the live view,
and the real-arm twin at 50 Hz.

The loop is :class:`~rmb_lerobot.envs.teleop.session.TeleopSession` with a keyboard device
(W and S pressed alternately, so every step solves IK), recording (teleop phase, the episode
written and discarded at the end) as an operator would. For each setup two runs:

- **cost**: the loop unpaced (``realtime=False``): its own time per step, keys to env step,
  recorder and live view included;
- **paced**: the loop paced to the env's period as ``rmb-teleop`` runs it: the achieved period
  between steps (p50 / p99) and the rate (steps / wall time) against the target.

The baseline, measured in the same run, is the MuJoCo loop with no camera and no live view;
each row's cost is also given as a ratio to it. Every camera setup is measured twice, back to
back: with the episode writer encoding in the loop's thread (``writer: sync``, as before the
background encoder) and on its background thread (``writer: background``, the default); a
line after each pair gives background / sync for the cost and the achieved rate, so the two
are compared under the same load even on a shared machine. The live view writes an ``.rrd``
file (this machine has no display). The twin is ``RealUR5eDemo`` with ``driver: sim``, without
a camera: a twin camera renders in its own thread and the env refuses a frame older than
500 ms, which a 640x480 software render on a loaded 2-core machine exceeds (a real RealSense
delivers its frames itself). Its env paces itself to the arm's 50 Hz ticks; its rows compare
the loop as ``rmb-teleop`` paces it with the env's pacing alone, back to back. ``--profile``
prints the
functions taking the most time in the costliest MuJoCo setup (a third, warm, unpaced run).
The load average is printed before and after: other processes share this machine.

    OMP_NUM_THREADS=1 MUJOCO_GL=egl .venv/bin/python benchmarks/teleop_rate.py --steps 150

``--writer sync|background`` measures one writer only, ``--only-twin`` the twin (and the
baseline).
"""

from __future__ import annotations

import argparse
import cProfile
import io
import os
import pstats
import tempfile
import time
from pathlib import Path

import numpy as np

from rmb_lerobot.envs.registry import entry_for
from rmb_lerobot.envs.teleop.keyboard import KeyboardDevice
from rmb_lerobot.envs.teleop.keys import ScriptedKeySource
from rmb_lerobot.envs.teleop.live_view import LiveView
from rmb_lerobot.envs.teleop.session import TeleopConfig, TeleopSession

SIZE = (640, 480)


class Ticks:
    """A step view that stamps each step's end, then hands on to the live view (if any)."""

    def __init__(self, view: LiveView | None):
        self.view = view
        self.ticks: list[float] = []

    def log_step(self, session: TeleopSession) -> None:
        if self.view is not None:
            self.view.log_step(session)
        self.ticks.append(time.monotonic())


def keys_for(steps: int) -> ScriptedKeySource:
    """n, n (recording from step 1), W / S alternately for ``steps`` steps, n, f (discard)."""
    events = [(0, "n"), (1, "n")]
    events += [(2 + k, "w" if k % 2 == 0 else "s") for k in range(steps)]
    events += [(steps + 2, "n"), (steps + 3, "f")]
    return ScriptedKeySource(events)


def run_loop(
    env,
    steps: int,
    realtime: bool,
    live_view: Path | None,
    profile: bool = False,
    background: bool = True,
):
    """One session of ``steps`` driving steps; returns the step periods (s) and the profile."""
    with tempfile.TemporaryDirectory() as out:
        view = LiveView(live_view) if live_view is not None else None
        ticks = Ticks(view)
        session = TeleopSession(
            env,
            KeyboardDevice(),
            keys_for(steps),
            TeleopConfig(out=Path(out), realtime=realtime, background_encoding=background),
            view=ticks,
            log=lambda message: None,
        )
        profiler = cProfile.Profile() if profile else None
        try:
            if profiler is not None:
                profiler.enable()
            session.run()
        finally:
            if profiler is not None:
                profiler.disable()
            if view is not None:
                view.close()
    periods = np.diff(ticks.ticks[2:])  # from the first recorded step on
    return periods, profiler


def row(name: str, cost: np.ndarray, paced: np.ndarray, target_hz: float, base: float) -> str:
    cost_ms = 1e3 * float(np.mean(cost))
    rate = 1.0 / float(np.mean(paced))
    return (
        f"| {name} | {cost_ms:.1f} | {cost_ms / base:.2f} | "
        f"{1e3 * np.percentile(paced, 50):.1f} | {1e3 * np.percentile(paced, 99):.1f} | "
        f"{rate:.2f} | {target_hz:.2f} | {'yes' if rate >= 0.98 * target_hz else 'no'} |"
    )


def mujoco_rows(
    steps: int, rrd_dir: Path, profile: bool, writers: list[str], baseline_only: bool = False
) -> tuple[list[str], str]:
    """The MuJoCo setups' rows (printed as they are measured) and the profile report."""
    setups = [
        ("MuJoCo cable, no camera, no live view (baseline)", (), False, True),
        ("MuJoCo cable, 1 camera 640x480 RGB-D", ("front",), False, True),
        ("MuJoCo cable, 1 camera 640x480 RGB-D + live view (.rrd)", ("front",), True, True),
        ("same, antialiasing off (--no-antialias) + live view (.rrd)", ("front",), True, False),
    ]
    if baseline_only:
        setups = setups[:1]
    rows, base, report = [], None, ""
    for name, cameras, live, antialias in setups:
        env = entry_for("cable").make(cameras=cameras, image_size=SIZE, antialias=antialias)
        measured = {}
        try:
            for writer in writers if cameras else ["background"]:
                background = writer == "background"
                rrd = rrd_dir / "cost.rrd" if live else None
                cost, _ = run_loop(env, steps, False, rrd, background=background)
                paced_rrd = rrd_dir / "paced.rrd" if live else None
                paced, _ = run_loop(env, steps, True, paced_rrd, background=background)
                base = base or 1e3 * float(np.mean(cost))
                label = f"{name}, writer: {writer}" if cameras else name
                rows.append(row(label, cost, paced, 1.0 / env.control_dt, base))
                print(rows[-1], flush=True)
                measured[writer] = (float(np.mean(cost)), float(np.mean(paced)))
                if profile and live and antialias and background:  # a third run, warm
                    _, profiler = run_loop(env, steps, False, rrd, profile=True)
                    stream = io.StringIO()
                    pstats.Stats(profiler, stream=stream).sort_stats("tottime").print_stats(14)
                    report = stream.getvalue()
        finally:
            env.close()
        if len(measured) == 2:
            (cost_s, paced_s), (cost_b, paced_b) = measured["sync"], measured["background"]
            print(
                f"|  background / sync: cost x{cost_b / cost_s:.2f}, "
                f"achieved rate x{paced_s / paced_b:.2f} | | | | | | | |",
                flush=True,
            )
    return rows, report


def twin_rows(steps: int, rrd_dir: Path, base: float) -> list[str]:
    """The UR5e twin's rows: the safety layer and the twin's SDK calls every step, no camera.

    Paced two ways, back to back: as ``rmb-teleop`` runs it (the loop sleeps to its deadlines
    and the env waits for the arm's tick) and by the env alone (``--no-realtime``): the twin's
    server threads run in this process and need the GIL, which the env's wait for the tick
    holds while it spins, so the two may differ."""
    from rmb_lerobot.envs.real.config import make_real_env

    env = make_real_env(
        "RealUR5eDemo",
        {
            "driver": "sim",
            "camera_configs": {},
            "watchdog_timeout": 10.0,  # a loaded machine stalls now and then: measure, not stop
        },
    )
    try:
        cost, _ = run_loop(env, steps, False, None)
        paced, _ = run_loop(env, steps, True, rrd_dir / "twin.rrd")
        env_only, _ = run_loop(env, steps, False, rrd_dir / "twin.rrd")
    finally:
        env.close()
    name = "RealUR5eDemo twin (driver: sim), no camera, + live view (.rrd)"
    target = 1.0 / env.control_dt
    return [
        row(f"{name}, loop and env paced (rmb-teleop)", cost, paced, target, base),
        row(f"{name}, env paced only (--no-realtime)", cost, env_only, target, base),
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=150, help="recorded steps per run")
    parser.add_argument("--no-twin", action="store_true", help="skip the real-arm twin")
    parser.add_argument("--only-twin", action="store_true", help="only the twin (and the baseline)")
    parser.add_argument("--profile", action="store_true", help="profile the live-view run")
    parser.add_argument(
        "--writer",
        choices=["both", "sync", "background"],
        default="both",
        help="episode writer encoding in the loop's thread (sync), on its background thread, "
        "or both back to back (default: both, for the ratio under the same load)",
    )
    args = parser.parse_args()
    writers = ["sync", "background"] if args.writer == "both" else [args.writer]
    print(f"load average before: {os.getloadavg()}, cores: {os.cpu_count()}")
    print(
        "| loop | cost / step (ms, unpaced) | cost / baseline | period p50 (ms, paced) "
        "| period p99 (ms) | achieved rate (Hz) | target (Hz) | target met |"
    )
    print("|---|---|---|---|---|---|---|---|", flush=True)
    with tempfile.TemporaryDirectory() as rrd_dir:
        rows, report = mujoco_rows(
            args.steps, Path(rrd_dir), args.profile, writers, baseline_only=args.only_twin
        )
        base = float(rows[0].split("|")[2])
        if not args.no_twin:
            for line in twin_rows(args.steps, Path(rrd_dir), base):
                print(line, flush=True)
    print(f"load average after: {os.getloadavg()}")
    if report:
        print("\nprofile of the unpaced live-view run (top functions by own time):\n" + report)


if __name__ == "__main__":
    main()
