"""Learning result: each policy trained from scripted demos, evaluated in every world.

Usage::

    .venv/bin/python benchmarks/learning.py [--env insert] [--episodes 50]
        [--policies act mlp sarnn dp3] [--steps N] [--batch-size B] [--eval-episodes 5]
        [--out outputs/learning]

Collects ``--episodes`` expert demonstrations (worlds cycled 0..5, front + hand cameras 64x64
with depth), converts them twice (RGB for act/mlp/sarnn; front depth for dp3), trains each
policy with the unmodified ``lerobot-train`` within a bounded CPU budget (each recipe's steps x
batch, about the same CPU time per policy; one torch thread per run, two runs side by side on
two cores) and evaluates the last checkpoint
with ``lerobot-eval`` ``--eval-episodes`` times in each world 0..5 (``--env.world_idx``).
Prints a markdown table for benchmarks/RESULTS.md. Stages whose output exists are skipped, so
an interrupted run resumes.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

from rmb_lerobot.cli.quickstart import ACT_CPU_ARGS, Stage, run
from rmb_lerobot.envs.registry import entry_for

WORLDS = range(6)
SIZE = 64
CAMERAS = ("front", "hand")


@dataclass(frozen=True)
class Recipe:
    """How one policy is trained: its dataset (RGB or depth), its options, its env inputs, and
    its budget (steps x batch), sized so that each run costs roughly the same CPU time."""

    dataset: str
    policy_args: tuple[str, ...]
    env_args: tuple[str, ...]
    steps: int = 1000
    batch_size: int = 16


RGB_ENV = (f"--env.cameras=[{','.join(CAMERAS)}]",)
DEPTH_ENV = ("--env.cameras=[front]", "--env.depth=true")
RECIPES = {
    "act": Recipe("rgb", ACT_CPU_ARGS, RGB_ENV),  # the main job's ACT
    "mlp": Recipe("rgb", ("--policy.optimizer_lr=1e-4",), RGB_ENV),
    # A SARNN sample is a whole 21-frame window (RMB trains on sequences): 200 x 8 windows is
    # about the CPU time of 1000 x 16 single frames for ACT or MLP on this machine.
    "sarnn": Recipe("rgb", (), RGB_ENV, steps=200, batch_size=8),
    "dp3": Recipe("depth", (), DEPTH_ENV),
    "flow_policy": Recipe("depth", (), DEPTH_ENV),  # DP3's inputs and CPU-sized U-Net
    # ManiFlow at its CPU size (the paper's 192 M parameters are for a GPU).
    "maniflow": Recipe(
        "rgb",
        (
            "--policy.n_layer=2",
            "--policy.n_head=4",
            "--policy.n_emb=64",
            "--policy.resnet_width=16",
        ),
        RGB_ENV,
    ),
}


def data_stages(args: argparse.Namespace) -> list[Stage]:
    entry = entry_for(args.env)
    rmb = args.out / "rmb"
    collect = Stage(
        "rmb-collect",
        [
            entry.rmb_env_name,
            f"--episodes={args.episodes}",
            f"--out={rmb}",
            "--cameras",
            *CAMERAS,
            "--image-size",
            str(SIZE),
            str(SIZE),
            "--success-only",
            "--workers=2",
        ],
    )
    rgb = Stage(
        "rmb-convert",
        ["to-lerobot", str(rmb), f"--output={args.out / 'rgb'}", "--repo-id=local/rgb"],
    )
    depth = Stage(
        "rmb-convert",
        [
            "to-lerobot",
            str(rmb),
            f"--output={args.out / 'depth'}",
            "--repo-id=local/depth",
            "--depth",
            "--camera-names",
            "front",
        ],
    )
    return [
        s
        for s, done in ((collect, rmb), (rgb, args.out / "rgb"), (depth, args.out / "depth"))
        if not done.exists()
    ]


def env_args(args: argparse.Namespace, recipe: Recipe) -> list[str]:
    entry = entry_for(args.env)
    return [
        f"--env.type={entry.lerobot_type}",
        f"--env.image_width={SIZE}",
        f"--env.image_height={SIZE}",
        *recipe.env_args,
    ]


def train_stage(args: argparse.Namespace, policy: str) -> Stage:
    recipe = RECIPES[policy]
    steps = args.steps or recipe.steps
    return Stage(
        "lerobot-train",
        [
            f"--dataset.repo_id=local/{recipe.dataset}",
            f"--dataset.root={args.out / recipe.dataset}",
            f"--policy.type={policy}",
            *recipe.policy_args,
            "--policy.device=cpu",
            "--policy.push_to_hub=false",
            *env_args(args, recipe),
            "--env_eval_freq=0",
            f"--steps={steps}",
            f"--batch_size={args.batch_size or recipe.batch_size}",
            f"--save_freq={steps}",
            f"--log_freq={max(1, steps // 20)}",
            "--num_workers=0",
            "--seed=1",
            f"--output_dir={args.out / 'train' / policy}",
            "--wandb.enable=false",
        ],
    )


def eval_stage(args: argparse.Namespace, policy: str, world: int) -> Stage:
    checkpoint = args.out / "train" / policy / "checkpoints" / "last" / "pretrained_model"
    return Stage(
        "lerobot-eval",
        [
            f"--policy.path={checkpoint}",
            "--policy.device=cpu",
            *env_args(args, RECIPES[policy]),
            f"--env.world_idx={world}",
            f"--eval.n_episodes={args.eval_episodes}",
            "--eval.batch_size=1",
            f"--seed={1000 + world}",  # object shifts unseen in training
            f"--output_dir={args.out / 'eval' / policy / f'world{world}'}",
        ],
    )


def train_and_evaluate(args: argparse.Namespace, policy: str) -> dict:
    """One policy: train (unless its checkpoint exists), then evaluate in each world."""
    train_s = None
    if not (args.out / "train" / policy / "checkpoints" / "last").exists():
        train_s = run(train_stage(args, policy), 1, 1)
    per_world = []
    for world in WORLDS:
        info_path = args.out / "eval" / policy / f"world{world}" / "eval_info.json"
        if not info_path.exists():
            run(eval_stage(args, policy, world), world + 1, len(WORLDS))
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
