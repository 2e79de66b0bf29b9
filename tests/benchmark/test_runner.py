"""A tiny grid end to end on a local Ray: real rmb-collect, rmb-convert, lerobot-train and
lerobot-eval cells, one of them failing on purpose; then resuming it.

The grid: Insert, 2 demos (32x32 front camera), an MLP trained 2 steps (evaluated by
lerobot-train after each step: a learning curve), evaluated 1 episode of 5 steps in worlds 0 and
1; and ``broken``, an MLP with an option LeRobot does not know, whose
training fails. The runs share one Ray session (module fixture) to pay its start-up once.
"""

from __future__ import annotations

import fcntl
import json
from pathlib import Path

import pytest

from rmb_lerobot.benchmark import load_config, run_benchmark
from rmb_lerobot.benchmark.report import CURVES_FILE, RESULTS_FILE, read_jsonl
from rmb_lerobot.benchmark.runner import BenchmarkBusyError

# The grid fixture (collect, convert, train, evaluate on Ray) took 235 s in a full `make test`,
# once 2069 s on a shared machine; it is set up within the first test's limit.
pytestmark = pytest.mark.timeout(2400)

GRID = {
    "tasks": ["insert"],
    "demos": 2,
    "seeds": [0],
    "worlds": [0, 1],
    "eval_episodes": 1,
    "episode_length": 5,
    "image_size": [32, 32],
    "cameras": ["front"],
    "video_codec": "h264",
    # lerobot-train evaluates the MLP after steps 1 and 2: the learning curve, from its log.
    "learning_curve": {"eval_freq": 1, "eval_episodes": 1, "policies": ["mlp"]},
    "policies": {
        "mlp": {"steps": 2, "batch_size": 2},
        "broken": {"recipe": "mlp", "steps": 2, "batch_size": 2, "options": {"no_such": 1}},
    },
}


@pytest.fixture(scope="module")
def ray_session():
    from rmb_lerobot.benchmark.runner import init_ray

    ray = init_ray(num_cpus=2)
    yield ray
    ray.shutdown()


@pytest.fixture(scope="module")
def grid(tmp_path_factory, ray_session):
    out = tmp_path_factory.mktemp("bench") / "out"
    config_file = out.parent / "grid.json"
    config_file.write_text(json.dumps({**GRID, "out": str(out)}))
    summary = run_benchmark(load_config(config_file), progress=False, echo=lambda line: None)
    return config_file, out, summary


def _mtimes(root: Path) -> dict[str, int]:
    return {str(p.relative_to(root)): p.stat().st_mtime_ns for p in root.rglob("*") if p.is_file()}


def test_tiny_grid_runs_every_cell_and_writes_rows_and_report(grid):
    _, out, summary = grid
    rows = {(r["policy"], r["world"]): r for r in read_jsonl(out / RESULTS_FILE)}
    assert set(rows) == {("mlp", 0), ("mlp", 1), ("broken", 0), ("broken", 1)}
    for world in (0, 1):
        row = rows["mlp", world]
        assert row["status"] == "ok", row["error"]
        assert row["n_episodes"] == 1 and row["n_successes"] in (0, 1)
        assert row["pc_success"] == 100.0 * row["n_successes"]
        assert row["train_s"] > 0 and row["eval_s"] > 0 and row["collect_s"] > 0
        assert (out / "eval/insert/mlp/seed0-n2" / f"world{world}" / "eval_info.json").exists()
    assert (out / "train/insert/mlp/seed0-n2/checkpoints/last/pretrained_model").is_dir()
    kinds = sorted(cid.split("/")[0] for cid in summary.ran)
    assert kinds == ["collect", "convert", "eval", "eval", "eval", "eval", "train", "train"]
    markdown = (out / "report" / "benchmark.md").read_text()
    assert "| mlp |" in markdown and "| broken | failed |" in markdown
    curve = read_jsonl(out / CURVES_FILE)
    assert [(c["policy"], c["step"], c["n_episodes"]) for c in curve] == [
        ("mlp", 1, 1),
        ("mlp", 2, 1),
    ]
    assert all(c["pc_success"] in (0.0, 100.0) for c in curve)
    for name in ("heatmap_policies.png", "bars_policies.png", "learning_curves.png"):
        assert (out / "report" / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_failing_cell_is_reported_while_the_others_finish(grid):
    _, out, summary = grid
    [failure] = summary.first_failures()
    assert failure.id == "train/insert/broken/seed0-n2"
    assert "lerobot-train exited with status 2" in failure.error
    assert "--policy.no_such=1" in failure.error  # LeRobot's own verdict, from the log's end
    rows = [r for r in read_jsonl(out / RESULTS_FILE) if r["policy"] == "broken"]
    assert [r["status"] for r in rows] == ["failed", "failed"]
    assert {r["failed_cell"] for r in rows} == {failure.id}
    assert not (out / "eval/insert/broken").exists()  # its evaluations never ran
    assert not (out / "cells/train/insert/broken").exists()  # no completion record: retried
    assert "train/insert/broken/seed0-n2" in (out / "report" / "benchmark.md").read_text()


def test_resume_skips_finished_cells_and_reruns_only_what_is_missing(grid):
    config_file, out, _ = grid
    config = load_config(config_file, {"only_policies": ["mlp"]})
    before = _mtimes(out / "cells") | _mtimes(out / "train") | _mtimes(out / "data")
    again = run_benchmark(config, progress=False, echo=lambda line: None)
    assert again.ran == []  # nothing submitted to Ray
    assert len(again.skipped) == 5  # collect, convert, train, 2 evals
    assert _mtimes(out / "cells") | _mtimes(out / "train") | _mtimes(out / "data") == before
    rows = read_jsonl(out / RESULTS_FILE)
    assert len(rows) == 4  # broken's failed rows are kept, not dropped

    # An evaluation whose record is gone runs again; nothing upstream of it does.
    (out / "cells/eval/insert/mlp/seed0-n2/world1.json").unlink()
    train_record = out / "cells/train/insert/mlp/seed0-n2.json"
    checkpoint = out / "train/insert/mlp/seed0-n2/checkpoints/last/pretrained_model"
    stamps = (train_record.stat().st_mtime_ns, _mtimes(checkpoint))
    third = run_benchmark(config, progress=False, echo=lambda line: None)
    assert third.ran == ["eval/insert/mlp/seed0-n2/world1"]
    assert third.results["eval/insert/mlp/seed0-n2/world1"].ok
    assert (train_record.stat().st_mtime_ns, _mtimes(checkpoint)) == stamps
    # The row of the re-run evaluation carries the training time recorded in the first run.
    row = next(r for r in read_jsonl(out / RESULTS_FILE) if (r["policy"], r["world"]) == ("mlp", 1))
    assert row["status"] == "ok" and row["train_s"] > 0


def test_one_driver_per_output_directory(tmp_path):
    config = load_config(None, {**GRID, "out": str(tmp_path)})
    with open(tmp_path / ".rmb-benchmark.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)  # as a running driver holds it
        with pytest.raises(BenchmarkBusyError, match="another rmb-benchmark is running"):
            run_benchmark(config, progress=False)
    assert not (tmp_path / "cells").exists()  # nothing started
