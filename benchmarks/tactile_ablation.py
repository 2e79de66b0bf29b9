"""Does touch help? One policy trained with and without the fingertip tactile images.

The same scripted demonstrations (recorded once with the front camera and both DIGIT images,
under a random object shift) are converted twice, with and without ``tactile_left`` /
``tactile_right``; LeRobot's ACT (the quick start's CPU recipe) is trained on each with the same
budget and seed, and ``lerobot-eval`` scores both on the same unseen seeds and shift::

    .venv/bin/python benchmarks/tactile_ablation.py [--env TactoSawyerSpoon] [--episodes 40]
        [--steps 1000] [--eval-episodes 10] [--random-shift 0.02] [--out outputs/tactile_ablation]

Every stage is an unmodified command-line tool (printed before it runs). Trainings run side by
side, one torch thread each.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

from rmb_lerobot.cli.quickstart import Stage, _list, act_train_stage
from rmb_lerobot.envs.registry import entry_for

TACTILE = ("tactile_left", "tactile_right")


def _run_all(stages: list[Stage]) -> float:
    """Run stages side by side (one torch thread each); raise if any fails."""
    env = {**os.environ, "HF_HUB_OFFLINE": "1", "WANDB_MODE": "disabled", "OMP_NUM_THREADS": "1"}
    start = time.perf_counter()
    procs = []
    for stage in stages:
        print(f"=== {stage}", flush=True)
        procs.append(subprocess.Popen(stage.argv(), env=env))
    for stage, proc in zip(stages, procs, strict=True):
        if proc.wait() != 0:
            raise SystemExit(f"tactile_ablation: {stage.name} failed (exit {proc.returncode})")
    return time.perf_counter() - start


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--env", default="TactoSawyerSpoon")
    parser.add_argument("--episodes", type=int, default=40)
    parser.add_argument("--image-size", type=int, nargs=2, default=[64, 64], metavar=("W", "H"))
    parser.add_argument("--steps", type=int, default=1000)
    parser.add_argument("--batch-size", type=int, default=8)
    parser.add_argument("--eval-episodes", type=int, default=10)
    parser.add_argument("--random-shift", type=float, default=0.02, help="metres, demos and eval")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--out", type=Path, default=Path("outputs/tactile_ablation"))
    args = parser.parse_args()
    entry = entry_for(args.env)
    width, height = args.image_size
    cameras = {"with touch": ("front", *TACTILE), "vision only": ("front",)}
    if args.out.exists():
        shutil.rmtree(args.out)
    rmb = args.out / "rmb"
    collect = Stage(
        "rmb-collect",
        [
            entry.rmb_env_name,
            f"--episodes={args.episodes}",
            f"--out={rmb}",
            "--cameras",
            *cameras["with touch"],
            "--image-size",
            str(width),
            str(height),
            "--no-depth",
            "--success-only",
            f"--random-shift={args.random_shift}",
            "--workers=2",
        ],
    )
    timings = {"collect": _run_all([collect])}
    runs = {name: args.out / name.replace(" ", "_") for name in cameras}
    converts, trains, evals = [], [], []
    for name, out in runs.items():
        env_args = [
            f"--env.type={entry.lerobot_type}",
            f"--env.cameras={_list(cameras[name])}",
            f"--env.image_width={width}",
            f"--env.image_height={height}",
        ]
        repo_id = f"local/{entry.task}_{out.name}"
        converts.append(
            Stage(
                "rmb-convert",
                [
                    "to-lerobot",
                    str(rmb),
                    f"--repo-id={repo_id}",
                    f"--output={out / 'dataset'}",
                    "--camera-names",
                    *cameras[name],
                ],
            )
        )
        trains.append(
            act_train_stage(
                repo_id,
                out / "dataset",
                env_args,
                out / "train",
                steps=args.steps,
                batch_size=args.batch_size,
                seed=args.seed,
                log_every=max(1, args.steps // 10),
                num_workers=0,
            )
        )
        evals.append(
            Stage(
                "lerobot-eval",
                [
                    f"--policy.path={out / 'train' / 'checkpoints' / 'last' / 'pretrained_model'}",
                    "--policy.device=cpu",
                    *env_args,
                    f"--env.random_shift={args.random_shift}",
                    f"--eval.n_episodes={args.eval_episodes}",
                    "--eval.batch_size=1",
                    f"--seed={args.seed + 1000}",  # unseen seeds: unseen shifts, worlds drawn
                    f"--output_dir={out / 'eval'}",
                ],
            )
        )
    timings["convert"] = _run_all(converts)
    timings["train"] = _run_all(trains)
    timings["eval"] = _run_all(evals)
    print(
        f"\n{entry.rmb_env_name}: {args.episodes} demos (shift {args.random_shift} m), ACT "
        f"{args.steps} steps x batch {args.batch_size}, {args.eval_episodes} eval episodes"
    )
    print("| policy input | success | mean return |")
    print("|---|---:|---:|")
    for name, out in runs.items():
        overall = json.loads((out / "eval" / "eval_info.json").read_text())["overall"]
        print(
            f"| {name} ({', '.join(cameras[name])}) | {overall['pc_success']:.0f} % | "
            f"{overall['avg_sum_reward']:.2f} |"
        )
    print("time: " + ", ".join(f"{k} {v / 60:.1f} min" for k, v in timings.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
