"""Table maths and plots on hand-written results: the paper's own numbers come out."""

from __future__ import annotations

import json

import pytest

from rmb_lerobot.benchmark.config import TableSpec, parse_config
from rmb_lerobot.benchmark.report import (
    CURVES_FILE,
    RESULTS_FILE,
    cell_stat,
    markdown_table,
    render_report,
    table_data,
    write_jsonl,
)

PNG = b"\x89PNG\r\n\x1a\n"
PAPER_TASKS = ["cable", "ring", "particle", "cloth", "door", "toolbox", "cabinet_slide", "insert"]


def row(policy, task, seed, world, successes, episodes=1, demos=50, status="ok"):
    return {
        "policy": policy,
        "task": task,
        "seed": seed,
        "demos": demos,
        "world": world,
        "status": status,
        "n_successes": successes if status == "ok" else None,
        "n_episodes": episodes if status == "ok" else None,
        "pc_success": 100 * successes / episodes if status == "ok" else None,
        "failed_cell": None if status == "ok" else f"train/{task}/{policy}/seed{seed}-n{demos}",
        "error": None if status == "ok" else "lerobot-train exited with status 1; ...\nboom",
    }


def per_seed(policy, task, successes_by_seed, worlds):
    """Rows giving each seed ``successes`` of ``worlds`` episodes (one episode per world)."""
    return [
        row(policy, task, seed, world, int(world < successes))
        for seed, successes in enumerate(successes_by_seed)
        for world in range(worlds)
    ]


def test_a_seed_pools_its_worlds_and_seeds_give_mean_and_sample_std():
    # The paper's MLP on Ring, "7% (±15)": four seeds 0 %, one 1 of 3 episodes.
    stat = cell_stat(per_seed("mlp", "ring", [0, 0, 0, 0, 1], worlds=3))
    assert stat.mean == pytest.approx(100 / 15)
    assert stat.std == pytest.approx(14.907, abs=1e-3)  # sample std (ddof 1); ddof 0 gives 13.3
    assert (stat.n_seeds, stat.n_expected, stat.complete) == (5, 5, True)
    # Unequal episode counts: a seed's rate is its successes over its episodes.
    pooled = cell_stat([row("a", "door", 0, 0, 1, 1), row("a", "door", 0, 1, 0, 3)])
    assert pooled.mean == 25 and pooled.std == 0


def test_markdown_table_reproduces_the_papers_cells_and_averages():
    # Task means of the paper's MLP and ACT rows (Table II), one seed of 100 episodes each, and
    # Diffusion on Cloth over five seeds of six worlds: 97% (±7).
    mlp = [0, 7, 0, 27, 10, 47, 23, 17]
    act = [73, 45, 27, 53, 55, 57, 13, 37]
    rows = [row("mlp", t, 0, 0, k, 100) for t, k in zip(PAPER_TASKS, mlp, strict=True)]
    rows += [row("act", t, 0, 0, k, 100) for t, k in zip(PAPER_TASKS, act, strict=True)]
    rows += per_seed("diffusion", "cloth", [6, 6, 6, 6, 5], worlds=6)
    rows += per_seed("sarnn", "ring", [0, 0, 0, 0, 1], worlds=3)
    table = TableSpec(
        "t", (("mlp", "MLP Policy"), ("act", "ACT"), ("diffusion", "DP"), ("sarnn", "SARNN"))
    )
    text = markdown_table(table_data(rows, table, PAPER_TASKS, demos=50))
    lines = text.splitlines()
    assert lines[0] == "| Policy \\ Task | " + " | ".join(PAPER_TASKS) + " | Average |"
    mlp_line = lines[2]
    assert mlp_line.startswith("| MLP Policy | 0% (±0) |")
    assert mlp_line.endswith("| 16.4% (±15) |")  # the paper's MLP average
    assert lines[3].endswith("| **45.0% (±18)** |")  # ACT's, the best average here: bold
    assert "| **97% (±7)** |" in lines[4]  # DP on Cloth, best in its column
    assert "7% (±15)" in lines[5]
    assert lines[4].count(" - |") == 7  # DP ran on Cloth only: "-" elsewhere, average of one
    assert lines[4].endswith("| 96.7% (±0) [1/8 tasks] |")  # not bold: partial


def test_failed_and_partial_cells_are_marked():
    rows = per_seed("act", "insert", [2, 1], worlds=2)
    rows.append(row("act", "insert", 2, 0, 0, status="failed"))  # third seed failed
    rows.append(row("mlp", "insert", 0, 0, 0, status="failed"))
    table = TableSpec("t", (("act", "ACT"), ("mlp", "MLP")))
    lines = markdown_table(table_data(rows, table, ["insert"], demos=50)).splitlines()
    assert lines[2] == "| ACT | 75% (±35) [2/3 seeds] | 75.0% (±0) [partial] |"  # no bold
    assert lines[3] == "| MLP | failed | - |"
    # Rows of another demo count (the data-size study) are not in the main table.
    other = per_seed("mlp", "insert", [2], worlds=2)
    for r in other:
        r["demos"] = 10
    lines = markdown_table(table_data(other, table, ["insert"], demos=50)).splitlines()
    assert lines[3] == "| MLP | - | - |"


def test_report_writes_tables_plots_curves_and_data_size(tmp_path):
    config = parse_config(
        {
            "out": str(tmp_path),
            "tasks": ["insert", "door"],
            "policies": ["act", "mlp"],
            "seeds": [0, 1],
            "demos": 4,
            "data_size": {"demos": [2]},
            "learning_curve": {"eval_freq": 10},
            "tables": {
                "main": {"title": "Main", "rows": {"act": "ACT", "mlp": "MLP"}},
                "cams": {"rows": ["act"], "tasks": ["insert"]},
            },
        }
    )
    rows = []
    for demos in (2, 4):
        for policy in ("act", "mlp"):
            for task in ("insert", "door"):
                rows += [{**r, "demos": demos} for r in per_seed(policy, task, [demos // 2, 1], 2)]
    rows.append(row("mlp", "door", 2, 0, 0, demos=4, status="failed"))
    write_jsonl(tmp_path / RESULTS_FILE, rows)
    curve = [
        {"policy": p, "task": t, "seed": s, "demos": 4, "step": step, "pc_success": step * 5.0}
        for p in ("act", "mlp")
        for t in ("insert", "door")
        for s in (0, 1)
        for step in (10, 20)
    ]
    (tmp_path / CURVES_FILE).write_text("".join(json.dumps(c) + "\n" for c in curve))
    written = render_report(tmp_path, config)
    names = sorted(p.name for p in written)
    assert names == sorted(
        [
            "benchmark.md",
            "heatmap_main.png",
            "bars_main.png",
            "heatmap_cams.png",
            "bars_cams.png",
            "learning_curves.png",
            "data_size.png",
        ]
    )
    for path in written[1:]:
        assert path.read_bytes()[:8] == PNG and path.stat().st_size > 5000
    markdown = (tmp_path / "report" / "benchmark.md").read_text()
    assert "## Main" in markdown and "## cams" in markdown
    assert "| ACT | **75% (±35)** | **75% (±35)** | **75.0% (±0)** |" in markdown
    assert "`train/door/mlp/seed2-n4`: lerobot-train exited with status 1; ... ... boom" in markdown
