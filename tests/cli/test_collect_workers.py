"""rmb-collect with worker processes never hangs: it ends, or fails with a clear error.

Issue 30: ``rmb-collect --workers 2`` sometimes never exited after its last episode (a worker
whose SIGTERM handler lost its exception stayed blocked on ``multiprocessing.Pool``'s queue lock,
which ``Pool.terminate`` holds, and was joined without a timeout), and a worker killed from
outside made ``imap_unordered`` wait for its episode for ever. Every run here is a subprocess
with a timeout, so a hang fails the test instead of hanging the suite.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from rmb_lerobot import open_episode

# A tiny run: Door's scripted expert, no images, 2 episodes on 2 workers (about 10 s here).
TINY = ["door", "--episodes", "2", "--workers", "2", "--cameras", "--no-depth"]
RUNS = 3  # per mode below
RUN_TIMEOUT_S = 150  # a run that has not ended by then hangs

# Spawned workers (``--multiprocessing-fork``) turn every SIGTERM disposition into "ignored":
# the state the old worker's handler left when its exception was lost (it had set SIGTERM to
# ignored first). A run must end without ever needing a worker's SIGTERM.
LOSE_SIGTERM = """
import signal, sys
if "--multiprocessing-fork" in sys.argv:
    _signal = signal.signal
    def _lose_sigterm(signum, handler):
        return _signal(signum, signal.SIG_IGN if signum == signal.SIGTERM else handler)
    signal.signal = _lose_sigterm
    _signal(signal.SIGTERM, signal.SIG_IGN)
"""


def start_collect(out: Path, workers: int) -> subprocess.Popen:
    """20 small Insert episodes, in a session of their own (signals reach the workers too)."""
    env = {**os.environ, "OMP_NUM_THREADS": "1", "MUJOCO_GL": "egl"}
    command = [sys.executable, "-m", "rmb_lerobot.cli.collect", "insert", "--episodes", "20"]
    command += ["--out", str(out), "--workers", str(workers), "--cameras", "front"]
    command += ["--image-size", "32", "32", "--no-depth"]
    return subprocess.Popen(
        command,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        start_new_session=True,
    )


def hidden(out: Path) -> list[str]:
    return sorted(p.name for p in out.iterdir() if p.name.startswith("."))


def assert_complete(path: Path) -> None:
    with open_episode(path) as ep:
        assert len(ep) > 10
        for key in ep:
            assert len(ep[key]) == len(ep), key


def _run_tiny(out: Path, env: dict[str, str]) -> tuple[int, str, str]:
    command = [sys.executable, "-m", "rmb_lerobot.cli.collect", *TINY, "--out", str(out)]
    process = subprocess.Popen(
        command,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        start_new_session=True,  # on a hang, its workers are killed with it
    )
    try:
        stdout, stderr = process.communicate(timeout=RUN_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)
        _, stderr = process.communicate()
        pytest.fail(f"rmb-collect --workers 2 hung after {RUN_TIMEOUT_S} s: {stderr[-2000:]}")
    return process.returncode, stdout, stderr


@pytest.mark.parametrize("lost_sigterm", [False, True], ids=["plain", "workers-lose-sigterm"])
def test_many_short_multi_worker_runs_all_end(tmp_path, lost_sigterm):
    env = {**os.environ, "OMP_NUM_THREADS": "1", "MUJOCO_GL": "egl"}
    if lost_sigterm:
        (tmp_path / "site").mkdir()
        (tmp_path / "site" / "sitecustomize.py").write_text(LOSE_SIGTERM)
        env["PYTHONPATH"] = os.pathsep.join([str(tmp_path / "site"), env.get("PYTHONPATH", "")])
    started = time.monotonic()
    for run in range(RUNS):
        out = tmp_path / f"run{run}"
        code, stdout, stderr = _run_tiny(out, env)
        assert code == 0, stderr[-2000:]
        assert "kept 2 episodes (2 successful of 2)" in stdout
        assert sorted(p.name for p in out.iterdir()) == [
            "MujocoUR5eDoor_world0_000.rmb",
            "MujocoUR5eDoor_world1_001.rmb",
        ]
    assert time.monotonic() - started < RUNS * RUN_TIMEOUT_S


def _worker_pids(out: Path) -> set[int]:
    """The pids of the processes recording now (each writer notes its pid in its lock)."""
    pids = set()
    for lock in out.glob(".*.lock"):
        try:
            pids.add(int(lock.read_text().split()[1]))
        except (FileNotFoundError, IndexError, ValueError):
            continue  # finished, or not written yet
    return pids


def _wait_for_workers(out: Path, process: subprocess.Popen, count: int) -> set[int]:
    deadline = time.monotonic() + 180
    while len(pids := _worker_pids(out)) < count:
        if process.poll() is not None:
            pytest.fail(f"rmb-collect ended early: {process.communicate()[1][-2000:]}")
        if time.monotonic() > deadline:
            os.killpg(process.pid, signal.SIGKILL)
            pytest.fail(f"{count} workers were not recording in time")
        time.sleep(0.01)
    return pids


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    stat = Path(f"/proc/{pid}/stat")
    return not (stat.exists() and stat.read_text().rsplit(")", 1)[1].split()[0] == "Z")


def test_a_worker_killed_from_outside_ends_the_run_with_a_clear_error(tmp_path):
    out = tmp_path / "demos"
    process = start_collect(out, 2)
    victim = min(_wait_for_workers(out, process, 1))
    os.kill(victim, signal.SIGKILL)  # e.g. the out-of-memory killer
    try:
        _, stderr = process.communicate(timeout=120)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)
        pytest.fail("rmb-collect hung after one of its workers was killed")

    assert process.returncode == 1, stderr[-2000:]
    assert "Traceback" not in stderr
    last = stderr.splitlines()[-1]
    assert last.startswith("rmb-collect: error: a worker process ended abruptly while recording")
    assert f"pid {victim} killed by SIGKILL" in last and str(out) in last
    assert hidden(out) == []  # the killed worker's temporary is removed too
    for path in out.iterdir():
        assert_complete(path)


def test_a_second_ctrl_c_stops_at_once(tmp_path):
    """The epilog's promise: the first Ctrl-C stops cleanly, a second one stops at once (the
    workers are killed; the next run removes what they left)."""
    out = tmp_path / "demos"
    process = start_collect(out, 2)
    workers = _wait_for_workers(out, process, 2)
    os.killpg(process.pid, signal.SIGINT)  # a terminal's Ctrl-C: the whole process group
    time.sleep(0.05)  # inside the first one's clean-up: it waits for the workers to stop
    os.killpg(process.pid, signal.SIGINT)
    try:
        _, stderr = process.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)
        pytest.fail("a second Ctrl-C did not stop rmb-collect")

    assert process.returncode == 128 + signal.SIGINT, stderr[-2000:]
    assert "interrupted again; stopped at once" in stderr and "Traceback" not in stderr
    deadline = time.monotonic() + 10
    while any(_alive(pid) for pid in workers):
        assert time.monotonic() < deadline, "the workers outlived a second Ctrl-C"
        time.sleep(0.05)
