"""``rmb-benchmark --ray-address`` on a real two-node Ray cluster on this machine.

``ray start --head`` on 127.0.0.1 and a second node joining it from 127.0.0.2 (also loopback),
each with one CPU and its own environment; the grid's outputs go to one path both nodes see. The
cells' commands are stand-ins (``fake_tools.py`` through the config's ``launcher``) that leave
what the real tools would, in seconds: the real tools on a real grid are test_runner's job; this
test is about the cluster. The worker node is killed while one of its evaluations runs: that
cell alone fails (``retries: 0``), the rest of the grid finishes on the head node, and a rerun
with the same ``--out`` runs only the failed cell.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import psutil
import pytest

from rmb_lerobot.benchmark.report import RESULTS_FILE, read_jsonl

pytestmark = [pytest.mark.integration, pytest.mark.timeout(300)]

RAY = Path(sys.executable).with_name("ray")
BENCHMARK = Path(sys.executable).with_name("rmb-benchmark")
FAKE_TOOLS = Path(__file__).with_name("fake_tools.py")
WORLDS = [0, 1, 2, 3, 4, 5]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def ray_start(args: list[str], env: dict[str, str], log: Path, root: Path) -> None:
    """``ray start ARGS``; a failure names Ray's verdict and the raylet's fatal log lines."""
    with open(log, "a") as stream:
        done = subprocess.run(
            [str(RAY), "start", *args], env=env, stdout=stream, stderr=stream, timeout=180
        )
    if done.returncode != 0:
        fatal = [
            line[:400]
            for raylet_log in root.glob("session_*/logs/raylet.out")
            for line in raylet_log.read_text(errors="replace").splitlines()
            if " C " in line[:60]
        ]
        last = log.read_text(errors="replace").strip().splitlines()[-1:]
        pytest.fail(f"ray start {' '.join(args[:2])} failed: {last}; raylet: {fatal}")


def cluster_processes(root: Path) -> list[psutil.Process]:
    """Every process of this test's cluster: their command lines name its temp dir."""
    found = []
    for process in psutil.process_iter(["cmdline"]):
        try:
            if any(str(root) in arg for arg in process.info["cmdline"] or ()):
                found.append(process)
        except (psutil.NoSuchProcess, psutil.AccessDenied):
            continue
    return found


def kill_tree(process: psutil.Process) -> None:
    try:
        family = [process, *process.children(recursive=True)]
    except psutil.NoSuchProcess:
        return
    for member in family:
        with contextlib.suppress(psutil.NoSuchProcess):
            member.send_signal(signal.SIGKILL)


@pytest.fixture
def cluster(tmp_path):
    """A head node (127.0.0.1) and a worker node (127.0.0.2), one CPU each; stopped (only
    their processes, found by temp dir) when the test ends, whatever happened."""
    # Ray's socket paths live under its temp dir and must stay under 107 characters: tmp_path
    # is too deep, so a short directory of /tmp, removed at the end.
    root = Path(tempfile.mkdtemp(prefix="rmbray"))
    marks = tmp_path / "marks"
    marks.mkdir()
    port, head_manager, worker_manager = free_port(), free_port(), free_port()
    base = {
        **os.environ,
        "RAY_USAGE_STATS_ENABLED": "0",
        # Loopback only: no token (Ray 2.60's `ray start --head` otherwise turns token auth on
        # and a joining node needs the token file of this machine's user).
        "RAY_AUTH_MODE": "disabled",
        "FAKE_TOOL_MARKS": str(marks),
        "FAKE_TOOL_SECONDS": "2",
        # A dead node is noticed in about 2 s instead of Ray's default ~30 s.
        "RAY_health_check_period_ms": "500",
        "RAY_health_check_failure_threshold": "4",
    }
    common = ["--num-cpus=1", f"--temp-dir={root}", "--disable-usage-stats"]
    log = tmp_path / "ray_start.log"
    try:
        ray_start(
            [
                "--head",
                "--node-ip-address=127.0.0.1",
                f"--port={port}",
                f"--node-manager-port={head_manager}",
                "--include-dashboard=false",
                *common,
            ],
            {**base, "RMB_TEST_NODE": "head"},
            log,
            root,
        )
        ray_start(
            [
                f"--address=127.0.0.1:{port}",
                "--node-ip-address=127.0.0.2",
                f"--node-manager-port={worker_manager}",
                '--resources={"second_node": 1}',
                *common,
            ],
            {**base, "RMB_TEST_NODE": "worker"},
            log,
            root,
        )
        yield {"address": f"127.0.0.1:{port}", "root": root, "marks": marks, "env": base}
    finally:
        for process in cluster_processes(root):
            kill_tree(process)
        shutil.rmtree(root, ignore_errors=True)


def worker_raylet(root: Path) -> psutil.Process:
    """The worker node's raylet (its workers and agents are its children)."""
    [raylet] = [
        p
        for p in cluster_processes(root)
        if Path(p.info["cmdline"][0]).name == "raylet"
        and "127.0.0.2" in " ".join(p.info["cmdline"])
    ]
    return raylet


def grid(out: Path) -> dict:
    return {
        "out": str(out),
        "tasks": ["insert"],
        "policies": {"mlp": {"steps": 2, "batch_size": 2}},
        "seeds": [0],
        "worlds": WORLDS,
        "demos": 6,
        "eval_episodes": 2,
        "cameras": ["front"],
        "launcher": [sys.executable, str(FAKE_TOOLS)],
        "retries": 0,  # a killed node's cell fails (with retries it would run again elsewhere)
    }


def run_benchmark(config: Path, cluster: dict, log: Path) -> subprocess.Popen:
    stream = open(log, "a")  # noqa: SIM115 (closed by the caller via wait_for)
    return subprocess.Popen(
        [str(BENCHMARK), str(config), "--ray-address", cluster["address"], "--no-progress"],
        env=cluster["env"],
        stdout=stream,
        stderr=subprocess.STDOUT,
    )


def wait_for(condition, timeout: float, what: str):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = condition()
        if value:
            return value
        time.sleep(0.1)
    raise AssertionError(f"timed out after {timeout} s waiting for {what}")


def test_a_killed_worker_node_fails_only_its_cell_and_a_rerun_finishes_the_grid(cluster, tmp_path):
    out = tmp_path / "shared" / "out"  # the path every node sees
    config = tmp_path / "grid.json"
    config.write_text(json.dumps(grid(out)))
    log = tmp_path / "rmb-benchmark.log"
    marks: Path = cluster["marks"]

    driver = run_benchmark(config, cluster, log)
    try:
        running = wait_for(
            lambda: [
                m
                for m in marks.iterdir()
                if "-worker-lerobot-eval-" in m.name and not m.name.endswith(".done")
            ],
            120,
            "an evaluation running on the worker node",
        )
        kill_tree(worker_raylet(cluster["root"]))
        status = driver.wait(timeout=120)
    finally:
        if driver.poll() is None:
            driver.kill()
    printed = log.read_text()
    assert status == 1, printed  # some cell failed

    # Both nodes ran cells before the kill; the killed cell is the only failure.
    nodes = {m.name.split("-")[1] for m in marks.iterdir()}
    assert nodes == {"head", "worker"}, sorted(m.name for m in marks.iterdir())
    killed_world = next(w for w in WORLDS if running[0].name.endswith(f"world{w}"))
    rows = {r["world"]: r for r in read_jsonl(out / RESULTS_FILE)}
    assert sorted(rows) == WORLDS
    failed = [w for w, r in rows.items() if r["status"] != "ok"]
    assert failed == [killed_world], printed
    assert rows[killed_world]["error"].startswith("Ray: "), rows[killed_world]["error"]
    assert f"FAILED eval/insert/mlp/seed0-n6/world{killed_world}" in printed
    for world, row in rows.items():
        if world != killed_world:
            assert row["n_successes"] == (2 if world % 2 == 0 else 0), row
    assert not (out / f"cells/eval/insert/mlp/seed0-n6/world{killed_world}.json").exists()

    # The rerun (one node left) runs only that cell and succeeds.
    def started() -> set[str]:  # a cell that began, done or not (".done" added at its end)
        return {m.name.removesuffix(".done") for m in marks.iterdir()}

    before = started()
    rerun = run_benchmark(config, cluster, log)
    assert rerun.wait(timeout=120) == 0, log.read_text()
    new = sorted(m.name for m in marks.iterdir() if m.name.removesuffix(".done") not in before)
    assert len(new) == 1 and "-head-lerobot-eval-" in new[0], new
    assert new[0].endswith(f"world{killed_world}.done"), new
    rows = read_jsonl(out / RESULTS_FILE)
    assert len(rows) == len(WORLDS) and all(r["status"] == "ok" for r in rows), rows
    assert {r["distinct_demos"] for r in rows} == {6}  # one trajectory per collect world
    assert "1 cells run, 8 done before, 0 failed" in log.read_text()
