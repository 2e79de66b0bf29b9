"""One cell of the grid: a command, the artefact it leaves, its log and its completion record.

A cell is done when its completion record (``OUT/cells/<id>.json``, written atomically after the
command succeeded and its artefact exists) is there and was written for the same command; then
it is never run again. A cell that fails leaves no record: the next run retries it. A record for
a *different* command (the config changed under the same output directory) is an error for
that cell, not a silent re-use of stale artefacts.

:func:`execute` runs in a Ray worker (or inline). It never raises for a failing command or an
upstream failure: it returns a failed :class:`CellResult` carrying the reason (the last lines of
the command's log), so one failing cell never stops the grid.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
import shlex
import shutil
import subprocess
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rmb_lerobot.benchmark.recipes import collect_covers
from rmb_lerobot.cli.quickstart import Stage

TAIL_LINES = 25


@dataclass(frozen=True)
class Cell:
    """One command of the grid and everything the runner needs to know about it."""

    id: str  # "train/insert/act/seed0-n50": also its record and log names under OUT
    kind: str  # collect | convert | train | eval
    stage: Stage
    output: Path  # what must exist once the command succeeded
    upstream: tuple[str, ...]  # ids of the cells it needs
    out: Path  # the benchmark's output directory (absolute)
    num_cpus: float = 1
    num_gpus: float = 0
    reset: tuple[Path, ...] = ()  # partial outputs of an earlier attempt, removed first
    key: tuple[tuple[str, Any], ...] = ()  # (policy, task, seed, demos, world, shift): rows
    inputs: tuple[Path, ...] = ()  # a convert cell's episodes (to count distinct demos)
    launcher: tuple[str, ...] = ()  # the config's command prefix (nice, a container, ...)

    @property
    def record(self) -> Path:
        return self.out / "cells" / f"{self.id}.json"

    @property
    def log(self) -> Path:
        return self.out / "logs" / f"{self.id}.log"

    def command(self) -> list[str]:
        """The command with the output directory written ``{out}``: the same grid moved to
        another mount point (a cluster's shared path) is still the same command."""
        root = str(self.out)
        words = (*self.launcher, self.stage.name, *self.stage.args)
        return [arg.replace(root, "{out}") for arg in words]


@dataclass
class CellResult:
    """What a cell produced, or why it failed. ``durations`` holds the seconds of this cell and
    of the cells it depended on, by kind (``collect_s``, ``train_s``, ...)."""

    id: str
    kind: str
    ok: bool
    seconds: float | None = None
    skipped: bool = False  # done in an earlier run
    error: str = ""
    failed_cell: str = ""  # the cell that failed (this one, or one upstream)
    data: dict[str, Any] = field(default_factory=dict)
    durations: dict[str, float | None] = field(default_factory=dict)


def merged_durations(upstream: Sequence[CellResult]) -> dict[str, float | None]:
    durations: dict[str, float | None] = {}
    for result in upstream:
        durations.update(result.durations)
    return durations


def execute(
    cell: Cell, upstream: Sequence[CellResult], cancel: threading.Event | None = None
) -> CellResult:
    """Run ``cell`` (its upstream cells' results given); never raises for a failure.

    ``cancel``, when set, stops the command (``KeyboardInterrupt`` in the calling thread): how
    the local executor stops the commands its threads run.
    """
    durations = merged_durations(upstream)
    failed = next((u for u in upstream if not u.ok), None)
    if failed is not None:
        return CellResult(
            cell.id,
            cell.kind,
            ok=False,
            error=f"not run: {failed.failed_cell or failed.id} failed: {failed.error}",
            failed_cell=failed.failed_cell or failed.id,
            durations=durations,
        )
    try:
        for path in cell.reset:
            _remove(path)
        cell.record.unlink(missing_ok=True)
        returncode, seconds = run_logged(
            cell.stage, cell.log, threads=cell.num_cpus, launcher=cell.launcher, cancel=cancel
        )
        if returncode != 0:
            reason = f"{cell.stage.name} exited with status {returncode}"
            return _failure(cell, f"{reason}; end of {cell.log}:\n{log_tail(cell.log)}", durations)
        if not cell.output.exists():
            return _failure(
                cell, f"{cell.stage.name} succeeded but left no {cell.output}", durations
            )
        data = cell_data(cell)
        write_record(cell, seconds, data)
    except Exception as error:
        return _failure(cell, f"{type(error).__name__}: {error}", durations)
    return CellResult(
        cell.id,
        cell.kind,
        ok=True,
        seconds=seconds,
        data=data,
        durations={**durations, f"{cell.kind}_s": seconds},
    )


def _failure(cell: Cell, error: str, durations: dict) -> CellResult:
    return CellResult(
        cell.id, cell.kind, ok=False, error=error, failed_cell=cell.id, durations=durations
    )


def _remove(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path)
    elif path.exists() or path.is_symlink():
        path.unlink()


def run_logged(
    stage: Stage,
    log: Path,
    threads: float = 1,
    launcher: Sequence[str] = (),
    cancel: threading.Event | None = None,
) -> tuple[int, float]:
    """Run ``stage`` (after the ``launcher`` prefix, if any) with stdout and stderr in ``log``;
    returns (exit status, seconds).

    Offline (no Hub, no wandb), headless rendering, and as many torch/OpenMP threads as the
    cell's CPUs. An exception here (e.g. Ray cancelling the task) stops the command too, and so
    does setting ``cancel`` (it raises ``KeyboardInterrupt`` here once the command is stopped).
    """
    log.parent.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ)
    env.setdefault("HF_HUB_OFFLINE", "1")
    env.setdefault("WANDB_MODE", "disabled")
    env.setdefault("MUJOCO_GL", "egl")
    env["OMP_NUM_THREADS"] = str(max(1, int(threads)))
    start = time.perf_counter()
    with open(log, "w") as stream:
        stream.write(f"$ {shlex.join(launcher) + ' ' if launcher else ''}{stage}\n")
        stream.flush()
        argv = [*launcher, *stage.argv()]
        process = subprocess.Popen(argv, stdout=stream, stderr=subprocess.STDOUT, env=env)
        try:
            returncode = _wait(process, cancel)
        finally:
            if process.poll() is None:  # interrupted: do not leave the command running
                process.terminate()
                try:
                    process.wait(timeout=15)
                except subprocess.TimeoutExpired:
                    process.kill()
                    process.wait()
    return returncode, time.perf_counter() - start


def _wait(process: subprocess.Popen, cancel: threading.Event | None) -> int:
    if cancel is None:
        return process.wait()
    while True:
        try:
            return process.wait(timeout=0.5)
        except subprocess.TimeoutExpired:
            if cancel.is_set():
                raise KeyboardInterrupt("cell cancelled") from None


def log_tail(log: Path, lines: int = TAIL_LINES) -> str:
    """The last ``lines`` lines of a log as a terminal would show them (progress-bar redraws,
    i.e. text before a carriage return, dropped)."""
    try:
        with open(log, errors="replace", newline="") as stream:  # keep the carriage returns
            text = stream.read()
    except OSError as error:
        return f"(no log: {error})"
    shown = [line.rsplit("\r", 1)[-1] for line in text.split("\n")]
    return "\n".join([line for line in shown if line.strip()][-lines:])[-8000:]


# ----------------------------------------------------------------------------- records
def write_record(cell: Cell, seconds: float, data: dict[str, Any]) -> None:
    """The completion record, written atomically (a reader never sees half a record)."""
    record = {
        "id": cell.id,
        "command": cell.command(),
        "seconds": seconds,
        "finished": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "data": data,
    }
    cell.record.parent.mkdir(parents=True, exist_ok=True)
    tmp = cell.record.with_name(f".{cell.record.name}.tmp-{os.getpid()}")
    tmp.write_text(json.dumps(record, indent=1))
    os.replace(tmp, cell.record)


def recorded(cell: Cell) -> CellResult | None:
    """The result of a cell done in an earlier run, a failure if it was done for another
    command, or None when it has to run."""
    try:
        record = json.loads(cell.record.read_text())
    except FileNotFoundError:
        return None
    except (OSError, ValueError):
        return None  # unreadable: run it again
    if not cell.output.exists():
        return None  # its artefact was removed: run it again
    command = record.get("command")
    same = command == cell.command()
    if not same and cell.kind == "collect" and isinstance(command, list):
        same = collect_covers(command, cell.command())  # e.g. a grid of fewer policies
    if not same:
        return CellResult(
            cell.id,
            cell.kind,
            ok=False,
            error=(
                f"{cell.id} was done with another command (the config changed for the same "
                f"output directory): recorded {record.get('command')}, now {cell.command()}; "
                f"remove {cell.record} and {cell.output} to redo it, or use another output "
                "directory"
            ),
            failed_cell=cell.id,
        )
    seconds = record.get("seconds")
    return CellResult(
        cell.id,
        cell.kind,
        ok=True,
        seconds=seconds,
        skipped=True,
        data=record.get("data", {}),
        durations={f"{cell.kind}_s": seconds},
    )


# ----------------------------------------------------------------------------- what cells yield
def cell_data(cell: Cell) -> dict[str, Any]:
    """What a finished cell reports: an evaluation's outcome, a training's learning curve."""
    if cell.kind == "eval":
        return eval_summary(cell.output)
    if cell.kind == "train":
        return {"curve": parse_learning_curve(cell.log), "final_loss": parse_final_loss(cell.log)}
    if cell.kind == "convert" and cell.inputs:
        return {"demos": len(cell.inputs), "distinct_demos": distinct_trajectories(cell.inputs)}
    return {}


def distinct_trajectories(episodes: Sequence[Path], decimals: int = 3) -> int:
    """How many of the RMB ``episodes`` differ in their commanded joint trajectory (rounded to
    ``decimals``, i.e. mrad): demos that replay one world's scene count once.

    Raises:
        ValueError: an episode has no ``command_joint_pos``.
    """
    import h5py

    seen = set()
    for episode in episodes:
        main = episode / "main.rmb.hdf5" if episode.is_dir() else episode
        with h5py.File(main, "r") as stream:
            if "command_joint_pos" not in stream:
                raise ValueError(f"{main}: no command_joint_pos; expected an RMB episode")
            commands = np.asarray(stream["command_joint_pos"], dtype=np.float64)
        commands = np.round(commands, decimals) + 0.0  # + 0.0: -0.0 hashes as 0.0
        seen.add((commands.shape, hashlib.sha256(commands.tobytes()).hexdigest()))
    return len(seen)


def eval_summary(eval_info: Path) -> dict[str, Any]:
    """Success rate and episode counts from ``lerobot-eval``'s ``eval_info.json``."""
    info = json.loads(eval_info.read_text())
    successes = [bool(s) for task in info.get("per_task", []) for s in task["metrics"]["successes"]]
    overall = info["overall"]
    episodes = int(overall.get("n_episodes", len(successes)))
    return {
        "pc_success": float(overall["pc_success"]),
        "n_episodes": episodes,
        "n_successes": sum(successes)
        if successes
        else round(float(overall["pc_success"]) * episodes / 100),
        "avg_sum_reward": float(overall.get("avg_sum_reward", math.nan)),
        "eval_s": float(overall.get("eval_s", math.nan)),
    }


# ``lerobot-train --env_eval_freq=N`` evaluates the policy every N steps and writes the outcome
# only to its log (and to wandb): "Eval policy at step N" and then, per suite, a line
# "Suite overall aggregated: {... 'pc_success': 40.0, 'n_episodes': 5, ...}" (LeRobot 0.6.1,
# lerobot/scripts/lerobot_train.py). Its checkpoints hold no evaluation results.
_EVAL_STEP = re.compile(r"Eval policy at step (\d+)")
_EVAL_OVERALL = re.compile(
    r"Suite overall aggregated: .*?'pc_success': ([-+\w.]+).*?'n_episodes': (\d+)"
)
_LOSS = re.compile(r"\bstep:\S+ .*?\bloss:([-+\d.eE]+|nan)")


def parse_learning_curve(log: Path | str) -> list[dict[str, float]]:
    """``[{"step": 250, "pc_success": 40.0, "n_episodes": 5}, ...]`` from a training log."""
    text = Path(log).read_text(errors="replace") if isinstance(log, Path) else log
    points, step = [], None
    for line in text.replace("\r", "\n").splitlines():
        if match := _EVAL_STEP.search(line):
            step = int(match.group(1))
        elif (match := _EVAL_OVERALL.search(line)) and step is not None:
            points.append(
                {
                    "step": step,
                    "pc_success": float(match.group(1)),
                    "n_episodes": int(match.group(2)),
                }
            )
            step = None
    return points


def parse_final_loss(log: Path | str) -> float | None:
    """The last training loss ``lerobot-train`` logged (None if it logged none)."""
    text = Path(log).read_text(errors="replace") if isinstance(log, Path) else log
    losses = _LOSS.findall(text.replace("\r", "\n"))
    return float(losses[-1]) if losses else None
