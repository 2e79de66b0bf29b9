"""rmb-collect under real signals: Ctrl-C, SIGTERM and kill -9 leave only complete episodes.

Each test runs ``rmb-collect`` as a subprocess in its own session (so a signal to its process
group reaches the workers as a terminal's Ctrl-C does), waits until an episode is being
recorded (a hidden temporary exists), and signals it.
"""

from __future__ import annotations

import logging
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from rmb_lerobot import open_episode
from rmb_lerobot.cli.collect import main
from rmb_lerobot.staging import Staging

SMALL = ["--image-size", "32", "32", "--cameras", "front", "--no-depth"]
MESSAGE = re.compile(
    r"rmb-collect: interrupted by (SIG\w+); kept (\d+) complete episodes? in (.+), "
    r"removed (\d+) partial ones?"
)


def start_collect(out: Path, workers: int, *extra: str) -> subprocess.Popen:
    env = {**os.environ, "OMP_NUM_THREADS": "1", "MUJOCO_GL": "egl"}
    command = [sys.executable, "-m", "rmb_lerobot.cli.collect", "insert", "--episodes", "20"]
    command += ["--out", str(out), "--workers", str(workers), *SMALL, *extra]
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


def wait_for_temporary(out: Path, process: subprocess.Popen, timeout: float = 120) -> None:
    deadline = time.monotonic() + timeout
    while not (out.is_dir() and any(name.endswith(".lock") for name in hidden(out))):
        if process.poll() is not None:
            pytest.fail(f"rmb-collect ended early: {process.communicate()[1][-2000:]}")
        if time.monotonic() > deadline:
            process.kill()
            pytest.fail("no episode was being recorded in time")
        time.sleep(0.01)


def assert_complete(path: Path) -> None:
    with open_episode(path) as ep:
        assert len(ep) > 10
        for key in ep:
            assert len(ep[key]) == len(ep), key
        assert ep["front_rgb_image"][len(ep) - 1].shape == (32, 32, 3)  # the last frame decodes


@pytest.mark.parametrize("workers", [1, 2])
@pytest.mark.parametrize(
    ("signum", "to_group"),
    [
        (signal.SIGINT, True),  # Ctrl-C in a terminal: the whole foreground process group
        (signal.SIGTERM, False),  # kill PID, docker stop, ...
    ],
    ids=["ctrl-c", "sigterm"],
)
def test_an_interrupt_keeps_complete_episodes_and_removes_partial_ones(
    tmp_path, workers, signum, to_group
):
    out = tmp_path / "demos"
    process = start_collect(out, workers)
    wait_for_temporary(out, process)
    (os.killpg if to_group else os.kill)(process.pid, signum)
    _, stderr = process.communicate(timeout=60)

    assert process.returncode == 128 + signum, stderr[-2000:]
    assert "Traceback" not in stderr
    ours = [line for line in stderr.splitlines() if line.startswith("rmb-collect")]
    assert len(ours) == 1 and stderr.splitlines()[-1] == ours[0], stderr[-2000:]
    name, kept, where, partial = MESSAGE.fullmatch(ours[0]).groups()
    assert name == signal.Signals(signum).name and where == str(out)
    assert hidden(out) == [], stderr[-2000:]
    episodes = sorted(out.iterdir())
    assert int(kept) == len(episodes) and int(partial) <= workers
    for path in episodes:
        assert_complete(path)


def test_a_killed_run_leaves_temporaries_that_the_next_run_removes(tmp_path, caplog):
    out = tmp_path / "demos"
    process = start_collect(out, 1)
    wait_for_temporary(out, process)
    process.send_signal(signal.SIGKILL)
    process.communicate(timeout=60)
    left = hidden(out)
    assert any(name.endswith(".lock") for name in left) and len(left) == 2  # no clean-up ran

    # A live writer's temporary (a parallel run): its lock is held, so it must stay.
    with Staging(out / "parallel.rmb") as live:
        live.path.mkdir()
        with caplog.at_level(logging.WARNING):
            code = main(
                ["insert", "--episodes", "1", "--world-idx", "5", "--out", str(out), *SMALL]
            )
        assert code == 0
        assert hidden(out) == sorted([live.path.name, live.lock_path.name])
    assert "removed 1 stale temporary left by ended processes" in caplog.text
    assert left[0] in caplog.text
    for path in out.iterdir():
        assert_complete(path)
