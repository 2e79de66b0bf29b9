"""Generalisation keys: demos collected under a random object shift, evaluations on shifts no demo
saw, and the report's seen / unseen columns with each task's distinct demo trajectories."""

from __future__ import annotations

import json
from pathlib import Path

import h5py
import numpy as np
import pytest

from rmb_lerobot.benchmark.cells import Cell, CellResult, cell_data, distinct_trajectories
from rmb_lerobot.benchmark.config import (
    BenchmarkConfigError,
    collect_seed_range,
    eval_seed_range,
    load_config,
    parse_config,
)
from rmb_lerobot.benchmark.grid import plan
from rmb_lerobot.benchmark.report import (
    RESULTS_FILE,
    render_report,
    result_row,
    row_key,
    write_jsonl,
)
from rmb_lerobot.cli.quickstart import Stage

PNG = b"\x89PNG\r\n\x1a\n"


def config(tmp_path, **extra):
    return parse_config(
        {
            "out": str(tmp_path / "out"),
            "tasks": ["insert"],
            "policies": {"mlp": {"steps": 2, "batch_size": 2}},
            "seeds": [0, 1],
            "worlds": [0, 1],
            "demos": 4,
            "eval_episodes": 2,
            **extra,
        }
    )


def test_shift_keys_reach_rmb_collect_and_add_one_unseen_evaluation_per_world(tmp_path):
    cells = plan(config(tmp_path, collect_shift=0.02, eval_shift=0.01))
    assert "--random-shift=0.02" in cells["collect/insert"].stage.args
    evals = {cid: c for cid, c in cells.items() if c.kind == "eval"}
    assert sorted(evals) == [
        f"eval/insert/mlp/seed{s}-n4/world{w}{suffix}"
        for s in (0, 1)
        for w in (0, 1)
        for suffix in ("", "-shift0.01")
    ]
    seen, unseen = (
        evals["eval/insert/mlp/seed1-n4/world1"],
        evals["eval/insert/mlp/seed1-n4/world1-shift0.01"],
    )
    assert not any(a.startswith("--env.random_shift") for a in seen.stage.args)
    assert "--env.random_shift=0.01" in unseen.stage.args
    assert dict(seen.key)["shift"] == 0.0 and dict(unseen.key)["shift"] == 0.01
    assert seen.output.parent != unseen.output.parent and seen.upstream == unseen.upstream
    # Without the keys the grid and its commands are what they were (records stay valid).
    plain = plan(config(tmp_path))
    assert not any("--random-shift" in " ".join(c.stage.args) for c in plain.values())
    assert len([c for c in plain.values() if c.kind == "eval"]) == 4


@pytest.mark.parametrize("collect_seed", [0, 7, 900])
def test_evaluation_seeds_never_replay_a_demos_seed(tmp_path, collect_seed):
    extra = {"collect_shift": 0.02, "eval_shift": 0.02, "collect_seed": collect_seed}
    if collect_seed == 900:  # 900 + 4 demos x 5 attempts reaches into eval seeds 1000..1102
        with pytest.raises(
            BenchmarkConfigError,
            match=r"eval_seed: evaluation seeds 910\.\.1012 overlap the demos. seeds 900\.\.919",
        ):
            config(tmp_path, **extra, eval_seed=910)
        return
    grid = config(tmp_path, **extra)
    collect, evaluate = set(collect_seed_range(grid)), set(eval_seed_range(grid))
    assert collect and evaluate and not collect & evaluate
    for cell in plan(grid).values():  # every evaluation's episodes lie in the checked range
        if cell.kind == "eval":
            start = int(next(a for a in cell.stage.args if a.startswith("--seed=")).split("=")[1])
            assert set(range(start, start + grid.eval_episodes)) <= evaluate


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        ({"eval_shift": 0}, "eval_shift: expected a shift > 0"),
        ({"eval_shift": -0.01}, "eval_shift: expected a number >= 0, got -0.01"),
        ({"collect_shift": "2cm"}, "collect_shift: expected a number >= 0, got '2cm'"),
        ({"collect_args": ["--random-shift=0.01"]}, "give the demos' object shift as collect"),
    ],
)
def test_bad_shift_keys_are_refused_naming_the_key(tmp_path, extra, message):
    with pytest.raises(BenchmarkConfigError, match=message):
        config(tmp_path, **extra)


def write_episode(path, commands):
    path.mkdir(parents=True)
    with h5py.File(path / "main.rmb.hdf5", "w") as stream:
        stream["command_joint_pos"] = np.asarray(commands, dtype=np.float64)


def test_distinct_trajectories_counts_replayed_scenes_once(tmp_path):
    rng = np.random.default_rng(0)
    base = rng.normal(size=(30, 7))
    paths = []
    for index, commands in enumerate(
        [base, base + 1e-6, base * 1.0, base[:-1], base + 0.01, -0.0 * base]
    ):
        paths.append(tmp_path / f"ep{index}.rmb")
        write_episode(paths[-1], commands)
    # base, base + 1e-6 (below a mrad) and base * 1.0 are one trajectory; the shorter one, the
    # shifted one and the zeros (-0.0 and 0.0 alike) are three more.
    assert distinct_trajectories(paths) == 4
    assert distinct_trajectories(paths[:3]) == 1
    write_episode(tmp_path / "zeros.rmb", 0.0 * base)
    assert distinct_trajectories([paths[-1], tmp_path / "zeros.rmb"]) == 1
    cell = Cell(
        "convert/insert/x",
        "convert",
        Stage("true", []),
        tmp_path,
        (),
        tmp_path,
        inputs=tuple(paths),
    )
    assert cell_data(cell) == {"demos": 6, "distinct_demos": 4}
    with h5py.File(tmp_path / "bad.hdf5", "w") as stream:
        stream["time"] = np.zeros(3)
    with pytest.raises(ValueError, match=r"bad\.hdf5: no command_joint_pos"):
        distinct_trajectories([tmp_path / "bad.hdf5"])


def test_report_shows_seen_and_unseen_side_by_side_with_distinct_demos(tmp_path):
    grid = config(tmp_path, eval_shift=0.02)
    out = grid.out
    cells = plan(grid)
    dataset = CellResult(
        "convert/insert/front_hand_n4", "convert", True, data={"distinct_demos": 2}
    )
    rows = []
    for cell in cells.values():
        if cell.kind != "eval":
            continue
        key = dict(cell.key)
        # Seen: every episode succeeds; unseen: seed 0 one of two, seed 1 none.
        successes = 2 if key["shift"] == 0 else (1 if key["seed"] == 0 else 0)
        result = CellResult(
            cell.id,
            "eval",
            True,
            data={"pc_success": 50.0 * successes, "n_episodes": 2, "n_successes": successes},
        )
        rows.append(result_row(grid, cell, result, dataset))
    assert len({row_key(r) for r in rows}) == len(rows) == 8
    assert {r["distinct_demos"] for r in rows} == {2}
    write_jsonl(out / RESULTS_FILE, rows)
    written = render_report(out, grid)
    markdown = (out / "report" / "benchmark.md").read_text()
    assert "| mlp | 100% (±0) |" in markdown  # the seen table is seen rows only
    assert "seen vs unseen placements (shifts up to 2 cm)" in markdown
    # unseen: seed 0 2 of 4 episodes (50 %), seed 1 0 of 4: 25 % (±35)
    assert "| mlp | 100% (±0) / 25% (±35) | 100.0% (±0) / 25.0% (±0) |" in markdown
    assert "| distinct demo trajectories | 2 of 4 | |" in markdown
    assert "from seeds no demo used" in markdown
    unseen_plot = out / "report" / "bars_policies_unseen.png"
    assert unseen_plot in written and unseen_plot.read_bytes()[:8] == PNG


def test_rows_written_before_the_shift_key_count_as_seen(tmp_path):
    grid = config(tmp_path, eval_shift=0.02)
    old = {"policy": "mlp", "task": "insert", "seed": 0, "demos": 4, "world": 0, "status": "ok"}
    old.update(n_successes=1, n_episodes=2, pc_success=50.0)
    assert row_key(old) == ("mlp", "insert", 0, 4, 0, 0.0)
    (grid.out).mkdir(parents=True)
    (grid.out / RESULTS_FILE).write_text(json.dumps(old) + "\n")
    render_report(grid.out, grid)
    markdown = (grid.out / "report" / "benchmark.md").read_text()
    assert "| mlp | 50% (±0) / - |" in markdown


def test_the_paper_scale_grid_is_8_tasks_4_policies_5_seeds_on_gpus_with_unseen_shifts():
    grid = load_config(Path(__file__).parents[2] / "benchmarks" / "grid_paper.yaml")
    assert len(grid.tasks) == 8 and len(grid.policies) == 4 and grid.seeds == tuple(range(5))
    assert grid.demos == 100 and grid.device == "cuda" and grid.collect_shift == 0.02
    assert grid.resources_for("train").num_gpus == 1
    kinds = [cell.kind for cell in plan(grid).values()]
    # The file's header counts these cells (and its cost estimate builds on them).
    assert [kinds.count(k) for k in ("collect", "convert", "train", "eval")] == [8, 8, 160, 1920]
    assert not set(collect_seed_range(grid)) & set(eval_seed_range(grid))


def test_the_unseen_grid_collects_and_evaluates_under_disjoint_shifts():
    config = load_config(Path(__file__).parents[2] / "benchmarks" / "grid_unseen.yaml")
    assert config.collect_shift == config.eval_shift == 0.02
    assert set(config.tasks) == {"insert", "door", "cabinet_slide", "cloth"}
    assert {p.name for p in config.policies} == {"mlp", "act", "diffusion", "sarnn"}
