"""Results rows, and the paper-style tables and plots made from them.

``results.jsonl`` holds one row per (policy, task, seed, demos, world, shift): the success rate
of the ``lerobot-eval`` run in that world (``shift`` 0: the world's own placement; > 0: object
placements shifted at random by up to that many metres, unseen in training), the number of
distinct demo trajectories the policy was trained on, its episode counts, the seconds each stage
took, and for a failed cell the reason (the end of the failing command's log). From these rows:

- a markdown table per configured table (rows: policies, columns: tasks and their average), each
  cell ``mean% (±std)`` over seeds as in the paper's Tables II and III: a seed's success rate
  pools its episodes over all evaluated worlds; the spread is the sample standard deviation over
  seeds (0 for one seed); the Average column is the mean over tasks of the task means, with the
  population standard deviation across tasks (which is how the paper's averages come out:
  ACT's 45.0 % (±18) from its eight task means);
- a heatmap and a grouped bar chart per table (matplotlib, Agg backend);
- with ``eval_shift``, per table the same cells on seen and unseen placements side by side, with
  each task's distinct demo trajectories, and a bar chart of both;
- the learning curves (success vs training step, from lerobot-train's periodic evaluation) and
  the data-size curves (success vs number of demos), mean ± std over seeds, one panel per policy.
"""

from __future__ import annotations

import json
import math
import os
import re
import statistics
from collections import defaultdict
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from rmb_lerobot.benchmark.cells import Cell, CellResult
    from rmb_lerobot.benchmark.config import BenchmarkConfig, TableSpec

RESULTS_FILE = "results.jsonl"
CURVES_FILE = "curves.jsonl"
REPORT_DIR = "report"
ROW_KEY = ("policy", "task", "seed", "demos", "world", "shift")


# ----------------------------------------------------------------------------- rows
def row_key(row: dict[str, Any]) -> tuple:
    """A row's identity; rows written before ``shift`` existed are shift 0 (seen worlds)."""
    return tuple(row.get(k, 0.0) if k == "shift" else row[k] for k in ROW_KEY)


def result_row(
    config: BenchmarkConfig, cell: Cell, result: CellResult, dataset: CellResult | None = None
) -> dict[str, Any]:
    """The results row of an ``eval`` cell; ``dataset``: the result of the convert cell its
    policy was trained from (for the number of distinct demos)."""
    key = {"shift": 0.0, **dict(cell.key)}
    policy = config.policy(key["policy"])
    data = result.data if result.ok else {}
    durations = result.durations
    return {
        **key,
        "status": "ok" if result.ok else "failed",
        "pc_success": data.get("pc_success"),
        "n_successes": data.get("n_successes"),
        "n_episodes": data.get("n_episodes"),
        "policy_type": policy.policy_type,
        "steps": policy.steps,
        "batch_size": policy.batch_size,
        "cameras": list(config.cameras_of(policy)),
        "depth": policy.depth,
        "distinct_demos": (dataset.data if dataset is not None else {}).get("distinct_demos"),
        "collect_s": durations.get("collect_s"),
        "convert_s": durations.get("convert_s"),
        "train_s": durations.get("train_s"),
        "eval_s": durations.get("eval_s"),
        "failed_cell": result.failed_cell or None,
        "error": result.error or None,
    }


def curve_rows(cell: Cell, result: CellResult) -> list[dict[str, Any]]:
    """Learning-curve points of a ``train`` cell, one row each."""
    key = dict(cell.key)
    return [{**key, **point} for point in result.data.get("curve", [])]


def read_jsonl(path: Path) -> list[dict[str, Any]]:
    """Rows of a JSON-lines file (none if it does not exist); errors name file and line."""
    try:
        lines = path.read_text().splitlines()
    except FileNotFoundError:
        return []
    rows = []
    for number, line in enumerate(lines, start=1):
        if line.strip():
            try:
                rows.append(json.loads(line))
            except ValueError as error:
                raise ValueError(f"{path}:{number}: not a JSON row: {error}") from None
    return rows


def write_jsonl(path: Path, rows: Iterable[dict[str, Any]]) -> None:
    """Replace ``path`` atomically with one JSON object per line."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    tmp.write_text("".join(json.dumps(row) + "\n" for row in rows))
    os.replace(tmp, path)


# ----------------------------------------------------------------------------- statistics
@dataclass(frozen=True)
class Stat:
    """Mean and spread of success rates (percent) over seeds, and how complete the cell is."""

    mean: float
    std: float
    n_seeds: int  # seeds with every world evaluated
    n_expected: int  # seeds in the results at all (complete, failed or partial)
    failed: bool = False  # some row of the cell failed

    @property
    def complete(self) -> bool:
        return self.n_seeds == self.n_expected and not self.failed


def seed_rates(rows: Sequence[dict[str, Any]]) -> tuple[dict[int, float], set[int], bool]:
    """Per seed, the success rate pooled over its worlds (only seeds whose rows are all ok);
    every seed seen; whether any row failed."""
    by_seed: dict[int, list[dict]] = defaultdict(list)
    for row in rows:
        by_seed[row["seed"]].append(row)
    rates, failed = {}, False
    for seed, seed_rows in by_seed.items():
        if any(r["status"] != "ok" for r in seed_rows):
            failed = True
            continue
        episodes = sum(r["n_episodes"] for r in seed_rows)
        if episodes:
            rates[seed] = 100.0 * sum(r["n_successes"] for r in seed_rows) / episodes
    return rates, set(by_seed), failed


def cell_stat(rows: Sequence[dict[str, Any]]) -> Stat | None:
    """Mean ± sample standard deviation over seeds of one (policy, task) cell; None if no rows."""
    if not rows:
        return None
    rates, seeds, failed = seed_rates(rows)
    values = list(rates.values())
    if not values:
        return Stat(math.nan, math.nan, 0, len(seeds), failed)
    std = statistics.stdev(values) if len(values) > 1 else 0.0
    return Stat(statistics.fmean(values), std, len(values), len(seeds), failed)


def average_stat(stats: Sequence[Stat | None]) -> Stat | None:
    """The Average column: mean over tasks of the task means, population std across tasks."""
    means = [s.mean for s in stats if s is not None and s.n_seeds]
    if not means:
        return None
    complete = all(s is not None and s.complete for s in stats)
    return Stat(
        statistics.fmean(means),
        statistics.pstdev(means),
        len(means),
        len(stats),
        failed=not complete,
    )


def select(rows: Iterable[dict], **match: Any) -> list[dict]:
    """The rows whose keys have the values given (a row without ``shift`` has shift 0)."""
    return [
        r
        for r in rows
        if all((r.get(k, 0.0) if k == "shift" else r.get(k)) == v for k, v in match.items())
    ]


# ----------------------------------------------------------------------------- tables
@dataclass(frozen=True)
class TableData:
    """One table's numbers: ``stats[row][column]`` with the task columns and the Average."""

    title: str
    labels: list[str]
    tasks: list[str]
    stats: list[list[Stat | None]]  # rows x (tasks + [average])


def table_data(
    rows: Sequence[dict],
    table: TableSpec,
    tasks: Sequence[str],
    demos: int,
    shift: float = 0.0,
    title: str | None = None,
) -> TableData:
    """One table's numbers from the rows evaluated with object shift ``shift`` (0: seen)."""
    tasks = list(table.tasks or tasks)
    stats = []
    for policy, _label in table.rows:
        line = [
            cell_stat(select(rows, policy=policy, task=t, demos=demos, shift=shift)) for t in tasks
        ]
        stats.append([*line, average_stat(line)])
    labels = [label for _, label in table.rows]
    return TableData(table.title if title is None else title, labels, tasks, stats)


def distinct_demos(rows: Sequence[dict], task: str, demos: int) -> int | None:
    """The distinct demo trajectories behind ``task``'s ``demos``-demo trainings (the most any
    of its datasets has; None if no row knows)."""
    counts = [
        r["distinct_demos"]
        for r in select(rows, task=task, demos=demos)
        if r.get("distinct_demos") is not None
    ]
    return max(counts) if counts else None


def generalisation_table(
    seen: TableData, unseen: TableData, rows: Sequence[dict], demos: int
) -> str:
    """Seen and unseen-shift success side by side per task (``seen / unseen``), and a last row
    with each task's distinct demo trajectories out of its demos."""
    header = "| Policy \\ Task (seen / unseen) | " + " | ".join([*seen.tasks, "Average"]) + " |"
    lines = [header, "|---|" + "---:|" * (len(seen.tasks) + 1)]
    for label, seen_line, unseen_line in zip(seen.labels, seen.stats, unseen.stats, strict=True):
        cells = [
            f"{format_stat(a, average=i == len(seen_line) - 1)} / "
            f"{format_stat(b, average=i == len(seen_line) - 1)}"
            for i, (a, b) in enumerate(zip(seen_line, unseen_line, strict=True))
        ]
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    counts = [distinct_demos(rows, task, demos) for task in seen.tasks]
    lines.append(
        "| distinct demo trajectories | "
        + " | ".join("-" if c is None else f"{c} of {demos}" for c in counts)
        + " | |"
    )
    return "\n".join(lines)


def format_stat(stat: Stat | None, average: bool = False) -> str:
    if stat is None:
        return "-"
    if not stat.n_seeds:
        return "failed" if stat.failed else "-"
    text = f"{stat.mean:.1f}%" if average else f"{stat.mean:.0f}%"
    text += f" (±{stat.std:.0f})"
    if not stat.complete:
        if average and stat.n_seeds == stat.n_expected:
            text += " [partial]"  # every task has a value, some from fewer seeds
        else:
            text += f" [{stat.n_seeds}/{stat.n_expected} {'tasks' if average else 'seeds'}]"
    return text


def markdown_table(data: TableData) -> str:
    """The table in the paper's layout; the best complete mean of each column in bold."""
    header = "| Policy \\ Task | " + " | ".join([*data.tasks, "Average"]) + " |"
    lines = [header, "|---|" + "---:|" * (len(data.tasks) + 1)]
    columns = list(zip(*data.stats, strict=True)) if data.stats else []
    best = [  # only complete cells compete: a partial average is not comparable
        max((s.mean for s in column if s is not None and s.complete), default=None)
        for column in columns
    ]
    for label, stats in zip(data.labels, data.stats, strict=True):
        cells = []
        for index, stat in enumerate(stats):
            text = format_stat(stat, average=index == len(stats) - 1)
            top = best[index] is not None and len(data.labels) > 1
            if top and stat is not None and stat.complete and math.isclose(stat.mean, best[index]):
                text = f"**{text}**"
            cells.append(text)
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def short_error(error: str) -> str:
    """The first and the last line of a cell's error (the command's verdict and its log's
    last line), without the "not run: X failed:" of cells downstream of the failure."""
    error = re.sub(r"^not run: \S+ failed: ", "", error or "")
    lines = [line.strip() for line in error.strip().splitlines() if line.strip()]
    if len(lines) <= 1:
        return lines[0] if lines else ""
    return f"{lines[0]} ... {lines[-1]}"


def describe(config: BenchmarkConfig) -> str:
    worlds = ", ".join(map(str, config.worlds))
    seeds = len(config.seeds)
    return (
        f"Mean success rate over {seeds} seed{'s' * (seeds != 1)} (± sample standard deviation "
        f"over seeds); a seed's rate pools {config.eval_episodes} episode"
        f"{'s' * (config.eval_episodes != 1)} in each of worlds {worlds}. Average: mean over "
        "tasks of the task means (± population standard deviation across tasks), as the "
        f"paper's Table II. {config.demos} expert demos per task; [k/n] marks cells with "
        "failed or missing runs ([partial]: an average over such cells; see results.jsonl)."
    ) + shifts(config)


def shifts(config: BenchmarkConfig) -> str:
    """The object shifts of the demos and of the evaluations, in words."""
    demos = (
        f" Demos: objects shifted at random by up to {100 * config.collect_shift:g} cm per demo."
        if config.collect_shift
        else " Demos: each world's own placement (no random shift)."
    )
    if not config.eval_shift:
        return demos + " Evaluated on the worlds' own placements only."
    return demos + (
        f" Unseen: the same worlds with objects shifted at random by up to "
        f"{100 * config.eval_shift:g} cm, from seeds no demo used."
    )


# ----------------------------------------------------------------------------- report
def render_report(out: Path, config: BenchmarkConfig) -> list[Path]:
    """Write ``report/benchmark.md`` and the plots from ``out``'s results; returns the files."""
    rows = read_jsonl(out / RESULTS_FILE)
    report = out / REPORT_DIR
    report.mkdir(parents=True, exist_ok=True)
    written: list[Path] = []
    sections = [f"# Benchmark results ({out})", "", describe(config), ""]
    for table in config.tables:
        data = table_data(rows, table, config.tasks, config.demos)
        sections += [f"## {data.title}", "", markdown_table(data), ""]
        for kind, plot in (("heatmap", plot_heatmap), ("bars", plot_bars)):
            path = report / f"{kind}_{table.name}.png"
            plot(data, path)
            written.append(path)
            sections += [f"![{kind}]({path.name})", ""]
        if config.eval_shift:
            cm = f"{100 * config.eval_shift:g} cm"
            unseen = table_data(
                rows, table, config.tasks, config.demos, config.eval_shift, f"{data.title}, unseen"
            )
            path = report / f"bars_{table.name}_unseen.png"
            plot_seen_unseen(data, unseen, path)
            written.append(path)
            sections += [
                f"## {data.title}: seen vs unseen placements (shifts up to {cm})",
                "",
                generalisation_table(data, unseen, rows, config.demos),
                "",
                f"![seen vs unseen]({path.name})",
                "",
            ]
    failures = [r for r in rows if r["status"] != "ok" and r.get("failed_cell")]
    if failures:
        origins: dict[str, str] = {}
        for row in failures:
            origins.setdefault(row["failed_cell"], row["error"] or "")
        sections += ["## Failed cells", ""]
        for origin, error in origins.items():
            sections.append(f"- `{origin}`: {short_error(error)}")
        sections.append("")
    curves = read_jsonl(out / CURVES_FILE)
    if curves:
        path = report / "learning_curves.png"
        plot_learning_curves(curves, path)
        written.append(path)
        sections += ["## Learning curves", "", f"![learning curves]({path.name})", ""]
    if config.data_size is not None:
        path = report / "data_size.png"
        if plot_data_size(rows, path):
            written.append(path)
            sections += ["## Success vs number of demos", "", f"![data size]({path.name})", ""]
    markdown = report / "benchmark.md"
    tmp = markdown.with_name(f".benchmark.md.tmp-{os.getpid()}")
    tmp.write_text("\n".join(sections))
    os.replace(tmp, markdown)
    return [markdown, *written]


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save(fig, path: Path) -> None:
    tmp = path.with_name(f".{path.stem}.tmp-{os.getpid()}{path.suffix}")
    fig.savefig(tmp, dpi=120, bbox_inches="tight")
    os.replace(tmp, path)


def plot_heatmap(data: TableData, path: Path) -> None:
    """Mean success per policy x task (and Average), annotated ``mean ±std``."""
    import numpy as np

    plt = _pyplot()
    columns = [*data.tasks, "Average"]
    means = np.array(
        [[s.mean if s is not None and s.n_seeds else np.nan for s in row] for row in data.stats],
        dtype=float,
    ).reshape(len(data.labels), len(columns))
    fig, ax = plt.subplots(figsize=(1.3 * len(columns) + 2, 0.6 * len(data.labels) + 1.6))
    cmap = plt.get_cmap("viridis").with_extremes(bad="#dddddd")  # grey: failed or not run
    image = ax.imshow(np.ma.masked_invalid(means), cmap=cmap, vmin=0, vmax=100, aspect="auto")
    ax.set_xticks(range(len(columns)), columns, rotation=30, ha="right")
    ax.set_yticks(range(len(data.labels)), data.labels)
    for i, row in enumerate(data.stats):
        for j, stat in enumerate(row):
            if stat is None or not stat.n_seeds:
                text = "failed" if stat is not None and stat.failed else "-"
            else:
                text = f"{stat.mean:.0f}\n±{stat.std:.0f}"
            color = "white" if means[i, j] < 60 else "black"  # NaN (grey): black
            ax.text(j, i, text, ha="center", va="center", fontsize=8, color=color)
    fig.colorbar(image, ax=ax, label="success rate (%)")
    ax.set_title(data.title)
    _save(fig, path)
    plt.close(fig)


def plot_bars(data: TableData, path: Path) -> None:
    """Grouped bars: per task (and Average) one bar per policy, error bars ± std over seeds."""
    import numpy as np

    plt = _pyplot()
    columns = [*data.tasks, "Average"]
    n = max(1, len(data.labels))
    width = 0.8 / n
    fig, ax = plt.subplots(figsize=(1.2 * len(columns) * max(1, n / 3) + 2, 3.5))
    x = np.arange(len(columns))
    for i, (label, row) in enumerate(zip(data.labels, data.stats, strict=True)):
        means = [s.mean if s is not None and s.n_seeds else 0.0 for s in row]
        stds = [s.std if s is not None and s.n_seeds else 0.0 for s in row]
        ax.bar(x + (i - (n - 1) / 2) * width, means, width, yerr=stds, capsize=2, label=label)
    ax.set_xticks(x, columns, rotation=30, ha="right")
    ax.set_ylabel("success rate (%)")
    ax.set_ylim(0, 105)
    ax.set_title(data.title)
    # Outside the axes: inside, it covers the bars' feet (0 % and low cells) whatever its corner.
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    _save(fig, path)
    plt.close(fig)


def plot_seen_unseen(seen: TableData, unseen: TableData, path: Path) -> None:
    """Per task (and Average) a pair of bars per policy: seen (solid) and unseen (hatched)."""
    import numpy as np

    plt = _pyplot()
    columns = [*seen.tasks, "Average"]
    n = max(1, len(seen.labels))
    width = 0.8 / n
    fig, ax = plt.subplots(figsize=(1.4 * len(columns) * max(1, n / 3) + 2, 3.5))
    x = np.arange(len(columns))
    for i, label in enumerate(seen.labels):
        offset = x + (i - (n - 1) / 2) * width
        for stats, part, hatch in ((seen, 0, None), (unseen, 1, "//")):
            row = stats.stats[i]
            means = [s.mean if s is not None and s.n_seeds else 0.0 for s in row]
            stds = [s.std if s is not None and s.n_seeds else 0.0 for s in row]
            ax.bar(
                offset + (part - 0.5) * width / 2,
                means,
                width / 2,
                yerr=stds,
                capsize=2,
                hatch=hatch,
                color=f"C{i}",
                edgecolor="black" if hatch else None,
                label=f"{label} ({'unseen' if part else 'seen'})",
            )
    ax.set_xticks(x, columns, rotation=30, ha="right")
    ax.set_ylabel("success rate (%)")
    ax.set_ylim(0, 105)
    ax.set_title(f"{seen.title}: seen (solid) vs unseen placements (hatched)")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    _save(fig, path)
    plt.close(fig)


def _mean_std_by(points: Iterable[tuple[Any, float]]) -> tuple[list, list[float], list[float]]:
    grouped: dict[Any, list[float]] = defaultdict(list)
    for x, y in points:
        grouped[x].append(y)
    xs = sorted(grouped)
    means = [statistics.fmean(grouped[x]) for x in xs]
    stds = [statistics.stdev(grouped[x]) if len(grouped[x]) > 1 else 0.0 for x in xs]
    return xs, means, stds


def _band(ax, xs, means, stds, label: str) -> None:
    """A mean line with its ± std band."""
    low = [m - s for m, s in zip(means, stds, strict=True)]
    high = [m + s for m, s in zip(means, stds, strict=True)]
    ax.plot(xs, means, marker="o", label=label)
    ax.fill_between(xs, low, high, alpha=0.2)


def _panels(policies: Sequence[str]):
    plt = _pyplot()
    fig, axes = plt.subplots(
        1, len(policies), figsize=(4 * len(policies), 3.2), squeeze=False, sharey=True
    )
    return plt, fig, dict(zip(policies, axes[0], strict=True))


def plot_learning_curves(curves: Sequence[dict], path: Path) -> None:
    """Success vs training step (lerobot-train's periodic evaluations), a panel per policy, a
    line per task, mean over seeds with ± std shaded."""
    policies = sorted({c["policy"] for c in curves})
    plt, fig, axes = _panels(policies)
    for policy, ax in axes.items():
        for task in sorted({c["task"] for c in curves if c["policy"] == policy}):
            points = [
                (c["step"], c["pc_success"]) for c in select(curves, policy=policy, task=task)
            ]
            xs, means, stds = _mean_std_by(points)
            _band(ax, xs, means, stds, task)
        ax.set_title(policy)
        ax.set_xlabel("training step")
        ax.set_ylim(-2, 102)
        ax.legend(fontsize=8)
    next(iter(axes.values())).set_ylabel("success rate (%)")
    _save(fig, path)
    plt.close(fig)


def plot_data_size(rows: Sequence[dict], path: Path) -> bool:
    """Success vs number of demos (seeds pooled over worlds as in the tables), a panel per
    policy, a line per task; False (nothing written) when no cell has two demo counts."""
    series: dict[tuple[str, str], list[tuple[int, float]]] = defaultdict(list)
    rows = select(rows, shift=0.0)
    for policy, task in sorted({(r["policy"], r["task"]) for r in rows}):
        for demos in sorted({r["demos"] for r in select(rows, policy=policy, task=task)}):
            rates, _, _ = seed_rates(select(rows, policy=policy, task=task, demos=demos))
            series[policy, task] += [(demos, rate) for rate in rates.values()]
    series = {k: v for k, v in series.items() if len({d for d, _ in v}) > 1}
    if not series:
        return False
    policies = sorted({p for p, _ in series})
    plt, fig, axes = _panels(policies)
    for (policy, task), points in series.items():
        ax = axes[policy]
        xs, means, stds = _mean_std_by(points)
        _band(ax, xs, means, stds, task)
    for policy, ax in axes.items():
        counts = sorted({d for (p, _), points in series.items() if p == policy for d, _ in points})
        ax.set_xticks(counts)
        ax.set_title(policy)
        ax.set_xlabel("demos")
        ax.set_ylim(-2, 102)
        ax.legend(fontsize=8)
    next(iter(axes.values())).set_ylabel("success rate (%)")
    _save(fig, path)
    plt.close(fig)
    return True
