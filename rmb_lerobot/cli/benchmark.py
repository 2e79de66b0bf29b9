"""``rmb-benchmark CONFIG | --example``: the paper's policies x tasks x seeds x worlds grid, on Ray.

Each cell is the unmodified command-line tool in a Ray task: ``rmb-collect`` (expert demos per
task), ``rmb-convert to-lerobot``, ``lerobot-train`` (per policy, task, seed) and ``lerobot-eval
--env.world_idx=K`` (per world). Cells done in an earlier run into the same ``--out`` are
skipped, a failing cell is reported and the rest goes on. Writes ``OUT/results.jsonl`` (one row
per policy, task, seed, world) and ``OUT/report/`` (markdown tables as the paper's Tables II and
III, heatmaps, bar charts, learning and data-size curves). Without a config file or
``--example`` (the built-in example grid) it prints its usage and exits 2: running a grid, hours
of CPU, is never a default.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from rmb_lerobot.benchmark.config import BenchmarkConfigError, load_config
from rmb_lerobot.cli.help import DefaultsHelpFormatter, apply_formatter
from rmb_lerobot.cli.sigterm import interrupted_signal, sigterm_as_keyboard_interrupt


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="rmb-benchmark",
        description="The paper's policies x tasks x seeds x worlds grid, on Ray: rmb-collect, "
        "rmb-convert, lerobot-train and lerobot-eval cells; results.jsonl and report/ in --out.",
        epilog="Options given here override the config file's keys. Local Ray by default (all "
        "CPUs of this machine, no dashboard); --ray-address joins a running cluster, where --out "
        "must be a path every node sees (a shared filesystem), with this package installed on "
        "every node; --executor local runs the cells without Ray. Exit status: 0 all cells "
        "succeeded, 1 some failed (see the report), 2 a "
        "bad config or command line (no CONFIG and no --example).",
    )
    parser.add_argument(
        "config",
        nargs="?",
        type=Path,
        help="YAML or JSON grid, e.g. benchmarks/grid_small.yaml "
        "(keys: rmb_lerobot/benchmark/config.py); required unless --example",
    )
    parser.add_argument(
        "--example",
        action="store_true",
        help="run the built-in example grid instead of a CONFIG: ACT on insert, seed 0, worlds "
        "0-5 (50 demos; 9 cells: collect, convert, train and 6 evaluations)",
    )
    grid = parser.add_argument_group("grid (override the config)")
    grid.add_argument("--out", type=Path, help="output directory (shared path on a cluster)")
    grid.add_argument("--policies", nargs="+", help="run only these policies of the config")
    grid.add_argument("--tasks", nargs="+", help="tasks, e.g. insert door cabinet_slide cloth")
    grid.add_argument("--seeds", nargs="+", type=int, help="training seeds")
    grid.add_argument("--worlds", nargs="+", type=int, help="evaluation worlds (0..5)")
    grid.add_argument("--demos", type=int, help="expert demos per task")
    grid.add_argument("--eval-episodes", type=int, help="episodes per world")
    grid.add_argument("--episode-length", type=int, help="eval step limit")
    grid.add_argument("--steps", type=int, help="training steps of every policy")
    grid.add_argument("--batch-size", type=int, help="batch size of every policy")
    grid.add_argument(
        "--num-workers",
        type=int,
        help="lerobot-train data-loader workers of every policy (on a GPU, video decoding is "
        "what a step waits for)",
    )
    grid.add_argument("--cameras", nargs="+", help="default cameras of the policies")
    grid.add_argument(
        "--image-size", nargs=2, type=int, metavar=("W", "H"), help="size of every camera"
    )
    grid.add_argument("--device", help="--policy.device for training and evaluation")
    ray = parser.add_argument_group("execution")
    ray.add_argument(
        "--executor",
        choices=("ray", "local"),
        default="ray",
        help="ray: cells as Ray tasks (local Ray or --ray-address); local: threads on this "
        "machine, no Ray needed (e.g. an offline GPU machine)",
    )
    ray.add_argument("--ray-address", help="an existing Ray cluster (e.g. auto, ray://host:10001)")
    ray.add_argument(
        "--num-cpus", type=int, help="CPUs of the local Ray or the local executor (default: all)"
    )
    ray.add_argument("--dry-run", action="store_true", help="list the cells and their commands")
    ray.add_argument("--report-only", action="store_true", help="only re-render OUT/report")
    ray.add_argument("--no-progress", action="store_true", help="no progress bar")
    return apply_formatter(parser, DefaultsHelpFormatter)


def overrides(args: argparse.Namespace) -> dict:
    return {
        "out": None if args.out is None else str(args.out),
        "only_policies": args.policies,
        "tasks": args.tasks,
        "seeds": args.seeds,
        "worlds": args.worlds,
        "demos": args.demos,
        "eval_episodes": args.eval_episodes,
        "episode_length": args.episode_length,
        "steps": args.steps,
        "batch_size": args.batch_size,
        "num_workers": args.num_workers,
        "cameras": args.cameras,
        "image_size": args.image_size,
        "device": args.device,
    }


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.config is None and not args.example:
        parser.error(
            "a grid needs a CONFIG file (e.g. benchmarks/grid_small.yaml) or --example for the "
            "built-in example grid"
        )
    if args.config is not None and args.example:
        parser.error(f"--example runs the built-in grid: give it or CONFIG {args.config}, not both")
    if args.executor == "local" and args.ray_address:
        parser.error(
            f"--ray-address {args.ray_address} joins a Ray cluster: not with --executor local"
        )
    try:
        config = load_config(args.config, overrides(args))
    except BenchmarkConfigError as error:
        print(f"rmb-benchmark: error: {error}", file=sys.stderr)
        return 2
    from rmb_lerobot.benchmark.cells import recorded
    from rmb_lerobot.benchmark.grid import plan
    from rmb_lerobot.benchmark.report import render_report, short_error
    from rmb_lerobot.benchmark.runner import BenchmarkBusyError, run_benchmark

    if args.dry_run:
        cells = plan(config)
        for cell in cells.values():
            done = recorded(cell)
            state = "todo" if done is None else ("done" if done.ok else "changed")
            print(f"[{state}] {cell.id}\n    {cell.stage}")
        print(f"{len(cells)} cells in {config.out.absolute()}")
        return 0
    if args.report_only:
        for path in render_report(config.out.absolute(), config):
            print(path)
        return 0
    try:
        with sigterm_as_keyboard_interrupt():  # a kill cancels running commands like Ctrl-C
            summary = run_benchmark(
                config,
                ray_address=args.ray_address,
                num_cpus=args.num_cpus,
                progress=not args.no_progress,
                executor=args.executor,
            )
    except KeyboardInterrupt as exc:
        signum = interrupted_signal(exc)
        print(
            f"rmb-benchmark: interrupted ({signum.name}); finished cells are kept, "
            "run again to resume"
        )
        return 128 + signum
    except BenchmarkBusyError as error:
        print(f"rmb-benchmark: error: {error}", file=sys.stderr)
        return 2
    print(
        f"{len(summary.ran)} cells run, {len(summary.skipped)} done before, "
        f"{len(summary.failed)} failed"
    )
    for failure in summary.first_failures():
        print(f"  FAILED {failure.id}: {short_error(failure.error)}")
    print(f"results: {config.out.absolute() / 'results.jsonl'}")
    for path in summary.report:
        print(f"report:  {path}")
    return 1 if summary.failed else 0


if __name__ == "__main__":
    sys.exit(main())
