"""``rmb-benchmark --executor local``: the grid on this machine's threads, with no Ray at all.

The cells' commands are the stand-ins of ``fake_tools.py`` (through the config's ``launcher``):
seconds instead of hours, while the runner's side (scheduling, records, resume, report) is the
real one. Ray is made unimportable for these tests, so they prove the executor needs none.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import psutil
import pytest

from rmb_lerobot.benchmark import load_config, run_benchmark
from rmb_lerobot.benchmark.report import RESULTS_FILE, read_jsonl

FAKE_TOOLS = Path(__file__).with_name("fake_tools.py")
WORLDS = [0, 1, 2, 3]


@pytest.fixture
def no_ray(monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)  # `import ray` raises ImportError


@pytest.fixture
def marks(tmp_path, monkeypatch) -> Path:
    marks = tmp_path / "marks"
    marks.mkdir()
    monkeypatch.setenv("FAKE_TOOL_MARKS", str(marks))
    monkeypatch.setenv("FAKE_TOOL_SECONDS", "0.5")
    return marks


def grid_file(tmp_path: Path, **changes) -> Path:
    grid = {
        "out": str(tmp_path / "out"),
        "tasks": ["insert"],
        "policies": {"mlp": {"steps": 2, "batch_size": 2}},
        "seeds": [0],
        "worlds": WORLDS,
        "demos": 4,
        "eval_episodes": 2,
        "cameras": ["front"],
        "launcher": [sys.executable, str(FAKE_TOOLS)],
        "resources": {"collect": {"num_cpus": 4}},  # more than the executor has: runs alone
        **changes,
    }
    path = tmp_path / "grid.json"
    path.write_text(json.dumps(grid))
    return path


def most_at_once(marks: Path) -> int:
    """The largest number of stand-in commands that ran at the same time."""
    events = []
    for mark in marks.glob("*.done"):
        events += [(int(mark.name.split("-")[0]), 1), (int(mark.read_text()), -1)]
    running = peak = 0
    for _, step in sorted(events):  # an end before a start at the same instant
        running += step
        peak = max(peak, running)
    return peak


def test_the_grid_runs_without_ray_two_cells_at_a_time_and_resumes(tmp_path, marks, no_ray):
    config = load_config(grid_file(tmp_path))
    summary = run_benchmark(config, executor="local", num_cpus=2, progress=False)

    kinds = sorted(cid.split("/")[0] for cid in summary.ran)
    assert kinds == ["collect", "convert", *["eval"] * len(WORLDS), "train"]
    assert not summary.failed
    rows = {r["world"]: r for r in read_jsonl(config.out / RESULTS_FILE)}
    assert sorted(rows) == WORLDS
    for world, row in rows.items():  # the stand-in evaluation succeeds in even worlds
        assert row["status"] == "ok" and row["n_successes"] == (2 if world % 2 == 0 else 0), row
        assert row["distinct_demos"] == 4 and row["collect_s"] > 0 and row["eval_s"] > 0
    assert summary.report and (config.out / "report" / "benchmark.md").exists()
    assert most_at_once(marks) == 2  # the four evaluations, two CPUs

    (config.out / "cells/eval/insert/mlp/seed0-n4/world3.json").unlink()
    again = run_benchmark(config, executor="local", num_cpus=2, progress=False)
    assert again.ran == ["eval/insert/mlp/seed0-n4/world3"]
    assert len(again.skipped) == 3 + len(WORLDS) - 1


def test_a_failing_cell_fails_its_dependents_and_the_rest_finishes(tmp_path, marks, no_ray):
    policies = {
        "mlp": {"steps": 2, "batch_size": 2},
        "broken": {"recipe": "mlp", "steps": 2, "batch_size": 2, "options": {"no_such": 1}},
    }
    config = load_config(grid_file(tmp_path, policies=policies, worlds=[0]))
    summary = run_benchmark(config, executor="local", num_cpus=2, progress=False)

    failed = {r.id: r for r in summary.failed}
    train, evaluation = "train/insert/broken/seed0-n4", "eval/insert/broken/seed0-n4/world0"
    assert set(failed) == {train, evaluation}
    assert "exited with status 2" in failed[train].error
    assert "unrecognized arguments: --policy.no_such=1" in failed[train].error
    assert failed[evaluation].failed_cell == train  # not run: its training failed
    rows = {r["policy"]: r for r in read_jsonl(config.out / RESULTS_FILE)}
    assert rows["mlp"]["status"] == "ok" and rows["broken"]["status"] != "ok"


def test_ctrl_c_stops_the_running_commands_and_keeps_finished_cells(
    tmp_path, marks, monkeypatch, no_ray, python_sigint
):
    monkeypatch.setenv("FAKE_TOOL_SECONDS", "60")
    config = load_config(grid_file(tmp_path))

    def interrupt_once_collect_runs():
        deadline = time.monotonic() + 60
        while not any("rmb-collect" in m.name for m in marks.iterdir()):
            if time.monotonic() > deadline:
                return
            time.sleep(0.05)
        os.kill(os.getpid(), signal.SIGINT)  # as a Ctrl-C in the terminal

    threading.Thread(target=interrupt_once_collect_runs, daemon=True).start()
    start = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        run_benchmark(config, executor="local", num_cpus=2, progress=False)
    assert time.monotonic() - start < 30  # not the stand-in's 60 s
    assert psutil.Process().children(recursive=True) == []  # the command was stopped
    assert not list(marks.glob("*.done"))
    assert not (config.out / "cells/collect/insert.json").exists()  # not recorded as done


def test_the_cli_refuses_a_ray_address_with_the_local_executor(tmp_path):
    done = subprocess.run(
        [
            str(Path(sys.executable).with_name("rmb-benchmark")),
            str(grid_file(tmp_path)),
            "--executor=local",
            "--ray-address=127.0.0.1:6379",
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 2
    assert "--ray-address 127.0.0.1:6379 joins a Ray cluster: not with --executor local" in (
        done.stderr
    )
