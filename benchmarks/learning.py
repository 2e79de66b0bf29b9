"""Learning result: each policy trained from scripted demos, evaluated in every world.

Usage::

    .venv/bin/python benchmarks/learning.py [--env insert] [--episodes 50]
        [--policies act mlp sarnn dp3] [--steps N] [--batch-size B] [--eval-episodes 5]
        [--out outputs/learning]

Collects ``--episodes`` expert demonstrations (worlds cycled 0..5, front + hand cameras 64x64
with depth), converts them twice (RGB; front depth for dp3 and flow_policy), trains each
policy with the unmodified ``lerobot-train`` within a bounded CPU budget (each recipe's steps x
batch, about the same CPU time per policy; one torch thread per run, two runs side by side on
two cores) and evaluates the last checkpoint
with ``lerobot-eval`` ``--eval-episodes`` times in each world 0..5 (``--env.world_idx``).
Prints a markdown table for benchmarks/RESULTS.md. Stages whose output exists are skipped, so
an interrupted run resumes.

The recipes and the command builders are ``rmb_lerobot.benchmark.recipes``, shared with
``rmb-benchmark`` (the same cells over policies x tasks x seeds, on Ray, with the paper's tables).
"""

from __future__ import annotations

import argparse
import json
import os
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from rmb_lerobot.benchmark.recipes import (
    RECIPES,
    EnvInputs,
    Recipe,
    TrainSpec,
    checkpoint_of,
    collect_stage,
    convert_stage,
    eval_stage,
    train_stage,
)
from rmb_lerobot.cli.quickstart import Stage, run
from rmb_lerobot.envs.registry import entry_for

WORLDS = range(6)
SIZE = 64
CAMERAS = ("front", "hand")
SEED = 1


def dataset_name(recipe: Recipe) -> str:
    return "depth" if recipe.depth else "rgb"


def data_stages(args: argparse.Namespace) -> list[Stage]:
    rmb = args.out / "rmb"
    size = (SIZE, SIZE)
    collect = collect_stage(args.env, rmb, args.episodes, CAMERAS, size, depth=True, workers=2)
    rgb = convert_stage([rmb], args.out / "rgb", "local/rgb")
    depth = convert_stage([rmb], args.out / "depth", "local/depth", cameras=["front"], depth=True)
    return [
        s
        for s, done in ((collect, rmb), (rgb, args.out / "rgb"), (depth, args.out / "depth"))
        if not done.exists()
    ]


def env_inputs(args: argparse.Namespace, recipe: Recipe) -> EnvInputs:
    return EnvInputs(args.env, recipe.cameras or CAMERAS, (SIZE, SIZE), depth=recipe.depth)


def train_dir(args: argparse.Namespace, policy: str) -> Path:
    return args.out / "train" / policy


def train_stage_of(args: argparse.Namespace, policy: str) -> Stage:
    recipe = RECIPES[policy]
    name = dataset_name(recipe)
    spec = TrainSpec(
        policy_type=recipe.policy_type,
        policy_args=recipe.policy_args,
        steps=args.steps or recipe.steps,
        batch_size=args.batch_size or recipe.batch_size,
        dataset=args.out / name,
        repo_id=f"local/{name}",
        env=env_inputs(args, recipe),
        output_dir=train_dir(args, policy),
        seed=SEED,
    )
    return train_stage(spec)


def eval_stage_of(args: argparse.Namespace, policy: str, world: int) -> Stage:
    return eval_stage(
        checkpoint_of(train_dir(args, policy)),
        env_inputs(args, RECIPES[policy]),
        world,
        args.eval_episodes,
        1000 + world,  # object shifts unseen in training
        args.out / "eval" / policy / f"world{world}",
    )


def train_and_evaluate(args: argparse.Namespace, policy: str) -> dict:
    """One policy: train (unless its checkpoint exists), then evaluate in each world."""
    train_s = None
    if not (train_dir(args, policy) / "checkpoints" / "last").exists():
        train_s = run(train_stage_of(args, policy), 1, 1)
    per_world = []
    for world in WORLDS:
        info_path = args.out / "eval" / policy / f"world{world}" / "eval_info.json"
        if not info_path.exists():
            run(eval_stage_of(args, policy, world), world + 1, len(WORLDS))
        per_world.append(json.loads(info_path.read_text())["overall"]["pc_success"])
    return {"policy": policy, "train_s": train_s, "per_world": per_world}


def table(results: list[dict], args: argparse.Namespace) -> str:
    header = "| policy | steps x batch | train min | " + " | ".join(f"w{w}" for w in WORLDS)
    lines = [header + " | all worlds |", "|---|---:|---:|" + "---:|" * len(WORLDS) + "---:|"]
    for r in results:
        recipe = RECIPES[r["policy"]]
        budget = f"{args.steps or recipe.steps} x {args.batch_size or recipe.batch_size}"
        minutes = "-" if r["train_s"] is None else f"{r['train_s'] / 60:.1f}"
        worlds = " | ".join(f"{s:.0f} %" for s in r["per_world"])
        mean = sum(r["per_world"]) / len(r["per_world"])
        lines.append(f"| {r['policy']} | {budget} | {minutes} | {worlds} | {mean:.0f} % |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--env", default="insert")
    parser.add_argument("--episodes", type=int, default=50)
    parser.add_argument("--policies", nargs="+", default=list(RECIPES), choices=list(RECIPES))
    parser.add_argument("--steps", type=int, default=None, help="all policies (default: own)")
    parser.add_argument("--batch-size", type=int, default=None, help="all policies")
    parser.add_argument("--eval-episodes", type=int, default=5, help="per world")
    parser.add_argument("--parallel", type=int, default=2, help="policies trained side by side")
    parser.add_argument("--out", type=Path, default=Path("outputs/learning"))
    args = parser.parse_args()

    os.environ.setdefault("OMP_NUM_THREADS", "1")  # one thread per run: no oversubscription
    start = time.perf_counter()
    for index, stage in enumerate(data_stages(args), start=1):
        run(stage, index, 3)
    with ThreadPoolExecutor(args.parallel) as pool:
        results = list(pool.map(lambda p: train_and_evaluate(args, p), args.policies))
    print(
        f"\n{args.episodes} demos of {entry_for(args.env).rmb_env_name}, {SIZE}x{SIZE} images, "
        f"{args.eval_episodes} eval episodes per world; "
        f"wall {(time.perf_counter() - start) / 60:.0f} min\n"
    )
    print(table(results, args))


if __name__ == "__main__":
    main()
