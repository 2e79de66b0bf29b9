"""What SART augmentation buys: one policy trained from 1 demo vs 1 demo + augmentation.

Usage::

    .venv/bin/python benchmarks/augmentation.py [--env insert] [--policy mlp] [--world 2]
        [--samples 16] [--radius 0.04] [--duration 1.0] [--steps 300] [--batch-size 16]
        [--eval-episodes 3] [--out outputs/augmentation]

One scripted demonstration in world ``--world`` (front + hand cameras 64x64, as
``benchmarks/learning.py``), ``rmb-augment --propose-regions`` around it (or ``--regions
YAML``; ``--samples`` per region), two datasets (the demo alone; the demo + its
augmentations) converted with ``rmb-convert to-lerobot``, and the same policy recipe and
training budget on each (``learning.py``'s recipes, train and eval stages: unmodified
``lerobot-train``, one torch thread, then ``lerobot-eval`` ``--eval-episodes`` times in each
world 0..5 with unseen seeds).
Prints a markdown table. Stages whose output exists are skipped, so an interrupted run resumes.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import learning

from rmb_lerobot import find_episodes, open_episode
from rmb_lerobot.cli.quickstart import Stage, run
from rmb_lerobot.envs.registry import entry_for

CONDITIONS = ("demo", "demo+sart")


def condition_args(args: argparse.Namespace, condition: str) -> argparse.Namespace:
    """What ``learning.train_and_evaluate`` needs, rooted in this condition's directory."""
    return argparse.Namespace(
        env=args.env,
        out=args.out / condition.replace("+", "_"),
        steps=args.steps,
        batch_size=args.batch_size,
        eval_episodes=args.eval_episodes,
    )


def data_stages(args: argparse.Namespace) -> list[Stage]:
    entry = entry_for(args.env)
    demo_dir, aug_dir = args.out / "rmb" / "demo", args.out / "rmb" / "sart"
    stages = []
    if not demo_dir.exists():
        stages.append(
            Stage(
                "rmb-collect",
                [
                    entry.rmb_env_name,
                    "--episodes=1",
                    f"--out={demo_dir}",
                    f"--world-idx={args.world}",
                    "--cameras",
                    *learning.CAMERAS,
                    "--image-size",
                    str(learning.SIZE),
                    str(learning.SIZE),
                    "--no-depth",
                    "--success-only",
                ],
            )
        )
    demo_episode = demo_dir / f"{entry.rmb_env_name}_world{args.world}_000.rmb"
    if not aug_dir.exists():
        stages.append(
            Stage(
                "rmb-augment",
                [
                    entry.rmb_env_name,
                    str(demo_episode),
                    *(
                        [f"--regions={args.regions}"]
                        if args.regions
                        else ["--propose-regions", f"--radius={args.radius}"]
                    ),
                    f"--duration={args.duration}",
                    f"--samples-per-region={args.samples}",
                    f"--out={aug_dir}",
                    "--seed=0",
                ],
            )
        )
    sources = {"demo": [demo_dir], "demo+sart": [demo_dir, aug_dir]}
    for condition in CONDITIONS:
        dataset = condition_args(args, condition).out / "rgb"
        if not dataset.exists():
            stages.append(
                Stage(
                    "rmb-convert",
                    [
                        "to-lerobot",
                        *map(str, sources[condition]),
                        f"--output={dataset}",
                        "--repo-id=local/rgb",
                    ],
                )
            )
    return stages


def frames(paths: list[Path]) -> int:
    total = 0
    for path in find_episodes(*paths):
        with open_episode(path) as episode:
            total += len(episode)
    return total


def table(results: dict[str, dict], args: argparse.Namespace) -> str:
    worlds = list(learning.WORLDS)
    header = "| training data | episodes | frames | train min | "
    header += " | ".join(f"w{w}" for w in worlds) + " | all worlds |"
    lines = [header, "|---|---:|---:|---:|" + "---:|" * len(worlds) + "---:|"]
    demo_dir, aug_dir = args.out / "rmb" / "demo", args.out / "rmb" / "sart"
    sources = {"demo": [demo_dir], "demo+sart": [demo_dir, aug_dir]}
    for condition, r in results.items():
        episodes = len(find_episodes(*sources[condition]))
        minutes = "-" if r["train_s"] is None else f"{r['train_s'] / 60:.1f}"
        cells = " | ".join(f"{s:.0f} %" for s in r["per_world"])
        mean = sum(r["per_world"]) / len(r["per_world"])
        lines.append(
            f"| {condition} | {episodes} | {frames(sources[condition])} | {minutes} | {cells} "
            f"| **{mean:.0f} %** |"
        )
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--env", default="insert")
    parser.add_argument("--policy", default="mlp", choices=list(learning.RECIPES))
    parser.add_argument("--world", type=int, default=2, help="world of the one demonstration")
    parser.add_argument("--samples", type=int, default=16, help="augmentations per region")
    parser.add_argument("--radius", type=float, default=0.04, help="metres, proposed regions")
    parser.add_argument(
        "--regions",
        type=Path,
        default=None,
        help="a regions YAML (rmb-augment --regions) instead of --propose-regions",
    )
    parser.add_argument("--duration", type=float, default=1.0, help="seconds per drive out")
    parser.add_argument("--steps", type=int, default=300, help="training steps (both runs)")
    parser.add_argument("--batch-size", type=int, default=16)
    parser.add_argument("--eval-episodes", type=int, default=3, help="per world")
    parser.add_argument("--parallel", type=int, default=2, help="runs trained side by side")
    parser.add_argument(
        "--train-arg",
        action="append",
        default=[],
        dest="policy_args",
        metavar="ARG",
        help="an extra lerobot-train option for both runs (repeatable; give it with '=', as "
        "the option starts with '--'), e.g. --train-arg="
        '\'--policy.normalization_mapping={"VISUAL": "MEAN_STD", "STATE": "IDENTITY", '
        '"ACTION": "IDENTITY"}\'',
    )
    parser.add_argument("--out", type=Path, default=Path("outputs/augmentation"))
    args = parser.parse_args()
    if args.policy_args:  # the same recipe for both runs, with these options added
        recipe = learning.RECIPES[args.policy]
        learning.RECIPES[args.policy] = dataclasses.replace(
            recipe, policy_args=(*recipe.policy_args, *args.policy_args)
        )

    os.environ.setdefault("OMP_NUM_THREADS", "1")
    start = time.perf_counter()
    stages = data_stages(args)
    for index, stage in enumerate(stages, start=1):
        run(stage, index, len(stages))
    with ThreadPoolExecutor(args.parallel) as pool:
        outcomes = pool.map(
            lambda c: learning.train_and_evaluate(condition_args(args, c), args.policy),
            CONDITIONS,
        )
        results = dict(zip(CONDITIONS, outcomes, strict=True))
    recipe = learning.RECIPES[args.policy]
    where = f"region of {args.regions}" if args.regions else f"proposed region ({args.radius} m)"
    print(
        f"\n{args.policy} ({args.steps} x {args.batch_size}, {learning.dataset_name(recipe)} "
        f"{'+'.join(learning.CAMERAS)} {learning.SIZE}x{learning.SIZE}) on "
        f"{entry_for(args.env).rmb_env_name}: 1 demo in world {args.world} vs + "
        f"{args.samples} SART samples per {where}; {args.eval_episodes} eval episodes per world; "
        f"wall {(time.perf_counter() - start) / 60:.0f} min\n"
    )
    if args.policy_args:
        print("extra training options: " + " ".join(args.policy_args) + "\n")
    print(table(results, args))


if __name__ == "__main__":
    main()
