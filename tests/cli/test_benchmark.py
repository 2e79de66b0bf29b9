"""``rmb-benchmark``: dry runs, config errors, re-rendering a report (the grid itself runs in
tests/benchmark/test_runner.py)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from rmb_lerobot.benchmark.report import RESULTS_FILE, write_jsonl
from rmb_lerobot.cli.benchmark import main

GRID_SMALL = Path(__file__).parents[2] / "benchmarks" / "grid_small.yaml"


def test_dry_run_lists_every_cell_with_its_command(tmp_path):
    script = Path(sys.executable).with_name("rmb-benchmark")
    result = subprocess.run(
        [str(script), str(GRID_SMALL), "--dry-run", "--out", str(tmp_path), "--tasks", "insert"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    # insert: 1 collect, 3 datasets (front+hand, front, hand), 6 trainings, 6 x 6 evaluations
    assert lines[-1] == f"46 cells in {tmp_path}"
    assert lines[0] == "[todo] collect/insert"
    assert lines[1].startswith(f"    rmb-collect MujocoUR5eInsert --episodes=50 --out={tmp_path}")
    assert "[todo] eval/insert/act_hand/seed0-n50/world5" in lines
    assert not any("door" in line for line in lines)


def test_a_bad_config_exits_2_naming_file_and_key(tmp_path, capsys):
    path = tmp_path / "grid.yaml"
    path.write_text("tasks: [insert]\npolicies:\n  act: {stpes: 10}\n")
    assert main([str(path), "--dry-run"]) == 2
    error = capsys.readouterr().err
    assert error.startswith(f"rmb-benchmark: error: {path}: policies.act: unknown key(s) ['stpes']")
    assert main([str(GRID_SMALL), "--policies", "pi0", "--dry-run"]) == 2
    assert "--policies pi0: not in the config's policies" in capsys.readouterr().err


def test_report_only_renders_the_results_of_a_directory(tmp_path, capsys):
    rows = [
        {
            "policy": "act",
            "task": "insert",
            "seed": seed,
            "demos": 50,
            "world": world,
            "status": "ok",
            "n_successes": successes,
            "n_episodes": 2,
            "pc_success": 50.0 * successes,
        }
        for seed, successes in ((0, 2), (1, 1))
        for world in range(6)
    ]
    write_jsonl(tmp_path / RESULTS_FILE, rows)
    narrow = ["--tasks", "insert", "--policies", "act", "--seeds", "0", "1"]
    code = main([str(GRID_SMALL), "--out", str(tmp_path), *narrow, "--report-only"])
    assert code == 0
    printed = capsys.readouterr().out.split()
    assert printed[0] == str(tmp_path / "report" / "benchmark.md")
    markdown = (tmp_path / "report" / "benchmark.md").read_text()
    assert "| ACT | 75% (±35) | 75.0% (±0) |" in markdown  # Table II: seeds 100 % and 50 %
    assert "| Front+Hand | 75% (±35) | 75.0% (±0) |" in markdown  # Table III: the same run
    assert all(Path(p).exists() for p in printed)


def test_sigterm_stops_the_running_cells_and_keeps_the_grid_resumable(tmp_path):
    """A ``kill`` acts like Ctrl-C: the running collection is cancelled, the driver exits 143,
    and nothing is recorded as done (a later run starts that cell again)."""
    import json
    import os
    import signal
    import time

    out = tmp_path / "out"
    config = tmp_path / "grid.json"
    grid = {"tasks": ["insert"], "demos": 500, "worlds": [0], "cameras": ["front"]}
    config.write_text(json.dumps({**grid, "image_size": [32, 32], "policies": {"mlp": {}}}))
    command = [sys.executable, "-m", "rmb_lerobot.cli.benchmark", str(config), "--out", str(out)]
    driver = subprocess.Popen(
        [*command, "--num-cpus", "1", "--no-progress"],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env={**os.environ, "OMP_NUM_THREADS": "1"},
    )
    collect_log = out / "logs" / "collect" / "insert.log"
    deadline = time.monotonic() + 120
    while not (collect_log.exists() and collect_log.stat().st_size) and driver.poll() is None:
        assert time.monotonic() < deadline, "the collection never started"
        time.sleep(0.5)
    driver.send_signal(signal.SIGTERM)
    output, _ = driver.communicate(timeout=120)

    assert driver.returncode == 128 + signal.SIGTERM, output
    assert "interrupted (SIGTERM)" in output
    assert not (out / "cells" / "collect" / "insert.json").exists()  # not recorded as done


def test_no_arguments_prints_usage_and_runs_nothing(tmp_path, capsys, monkeypatch):
    """A grid is hours of CPU: it needs a CONFIG or an explicit --example (issue 30)."""
    import pytest

    from rmb_lerobot.benchmark import runner

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(runner, "run_benchmark", lambda *a, **k: pytest.fail("a grid started"))
    with pytest.raises(SystemExit) as info:
        main([])
    assert info.value.code == 2
    error = capsys.readouterr().err
    assert error.startswith("usage: rmb-benchmark")
    assert "a grid needs a CONFIG file" in error and "--example" in error
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(SystemExit):
        main([str(GRID_SMALL), "--example", "--dry-run"])
    assert "not both" in capsys.readouterr().err


def test_example_is_the_built_in_grid(tmp_path, capsys):
    assert main(["--example", "--dry-run", "--out", str(tmp_path)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[-1] == f"9 cells in {tmp_path}" and lines[0] == "[todo] collect/insert"
