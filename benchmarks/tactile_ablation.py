"""Does touch help? One policy trained with and without the fingertip tactile images.

The same scripted demonstrations (recorded once with the front camera and both DIGIT images,
under a random object shift) are converted twice, with and without ``tactile_left`` /
``tactile_right``; LeRobot's ACT (the quick start's CPU recipe) is trained on each with the same
budget and seeds, and ``lerobot-eval`` scores every checkpoint on the same unseen seeds and
shift::

    .venv/bin/python benchmarks/tactile_ablation.py [--env TactoSawyerSpoon] [--episodes 40]
        [--steps 1000] [--batch-size 8] [--seeds 1] [--device cpu] [--num-workers 0]
        [--eval-episodes 10] [--random-shift 0.02] [--out outputs/tactile_ablation]
        [--stage all|collect|train|eval] [--jobs N]

``--stage all`` (the default) runs everything from scratch into ``--out`` (removed first);
``collect`` records and converts the demonstrations; ``train`` trains on the datasets already in
``--out`` (e.g. on a GPU machine: ``--device cuda --num-workers 3``); ``eval`` scores the
checkpoints already there (``lerobot-eval`` on the CPU, which is where pybullet is). With one
training seed a policy's folders are ``<out>/<arm>/train`` and ``eval``; with several,
``train_seed<N>`` and ``eval_seed<N>``. Only ``--device`` and the budget (steps, batch size)
change the recipe; every policy is evaluated on the same seeds (``--eval-seed``, default
1000 + the first training seed).

Every stage is an unmodified command-line tool (printed before it runs, its output also written
to ``<its folder>.log``). Stages run side by side (at most ``--jobs`` at a time), one torch
thread each. The summary (success per policy and seed, final training loss, and a Wilson 95 %
interval per arm, all seeds pooled) is printed and written to ``<out>/summary.json``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import threading
import time
from pathlib import Path

from rmb_lerobot.cli.quickstart import Stage, _list, act_train_stage
from rmb_lerobot.envs.registry import entry_for

TACTILE = ("tactile_left", "tactile_right")
CAMERAS = {"with touch": ("front", *TACTILE), "vision only": ("front",)}
STAGES = ("all", "collect", "train", "eval")


def _tee(stream, log: Path) -> None:
    """Copy a process' output to this console and to its log file."""
    with log.open("w") as f:
        for line in iter(stream.readline, ""):
            sys.stdout.write(line)
            sys.stdout.flush()
            f.write(line)
            f.flush()


def _run_all(stages: list[tuple[Stage, Path]], jobs: int | None = None) -> float:
    """Run stages side by side, at most ``jobs`` at a time (one torch thread each), each one's
    output also written to its log file; raise if any fails."""
    env = {**os.environ, "HF_HUB_OFFLINE": "1", "WANDB_MODE": "disabled", "OMP_NUM_THREADS": "1"}
    start = time.perf_counter()
    pending = list(stages)
    running: list[tuple[Stage, subprocess.Popen, threading.Thread]] = []
    failed = []
    while pending or running:
        while pending and (jobs is None or len(running) < jobs):
            stage, log = pending.pop(0)
            print(f"=== {stage}  (log: {log})", flush=True)
            log.parent.mkdir(parents=True, exist_ok=True)
            proc = subprocess.Popen(
                stage.argv(),
                env=env,
                stdout=subprocess.PIPE,
                stderr=subprocess.STDOUT,
                text=True,
                bufsize=1,
            )
            tee = threading.Thread(target=_tee, args=(proc.stdout, log), daemon=True)
            tee.start()
            running.append((stage, proc, tee))
        time.sleep(0.5)
        for item in list(running):
            stage, proc, tee = item
            if proc.poll() is not None:
                tee.join()
                running.remove(item)
                if proc.returncode != 0:
                    failed.append(f"{stage.name} (exit {proc.returncode})")
    if failed:
        raise SystemExit("tactile_ablation: failed: " + ", ".join(failed))
    return time.perf_counter() - start


def wilson(successes: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """Wilson score interval (95 % by default) of a success rate."""
    if n == 0:
        return (0.0, 1.0)
    p = successes / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return (max(0.0, centre - half), min(1.0, centre + half))


def final_loss(log: Path) -> tuple[str, float] | None:
    """The last ``step:`` and ``loss:`` that ``lerobot-train`` logged, if its log is there."""
    if not log.exists():
        return None
    found = re.findall(r"\bstep:(\S+) .*?\bloss:([0-9.]+)", log.read_text(errors="replace"))
    return (found[-1][0], float(found[-1][1])) if found else None


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--env", default="TactoSawyerSpoon")
    parser.add_argument("--episodes", type=int, default=40)
    parser.add_argument("--image-size", type=int, nargs=2, default=[64, 64], metavar=("W", "H"))
    parser.add_argument("--steps", type=int, default=1000)
    parser.add_argument("--batch-size", type=int, default=8)
    parser.add_argument("--eval-episodes", type=int, default=10)
    parser.add_argument("--random-shift", type=float, default=0.02, help="metres, demos and eval")
    parser.add_argument("--seed", type=int, default=1, help="training seed (one per arm)")
    parser.add_argument(
        "--seeds", type=int, nargs="+", default=None, help="several seeds (overrides --seed)"
    )
    parser.add_argument("--eval-seed", type=int, default=None, help="default: 1000 + first seed")
    parser.add_argument("--device", default="cpu", help="training device (eval stays on the CPU)")
    parser.add_argument("--num-workers", type=int, default=0, help="loader workers per training")
    parser.add_argument(
        "--save-freq", type=int, default=None, help="checkpoint every N steps (default: at the end)"
    )
    parser.add_argument("--stage", choices=STAGES, default="all")
    parser.add_argument("--jobs", type=int, default=None, help="stages side by side (default: all)")
    parser.add_argument("--out", type=Path, default=Path("outputs/tactile_ablation"))
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    entry = entry_for(args.env)
    width, height = args.image_size
    seeds = args.seeds or [args.seed]
    eval_seed = args.eval_seed if args.eval_seed is not None else seeds[0] + 1000
    do = {s: args.stage in ("all", s) for s in STAGES[1:]}
    if args.stage == "all" and args.out.exists():
        shutil.rmtree(args.out)
    rmb = args.out / "rmb"
    runs = {name: args.out / name.replace(" ", "_") for name in CAMERAS}

    def suffix(seed: int) -> str:
        return "" if len(seeds) == 1 else f"_seed{seed}"

    timings = {}
    if do["collect"]:
        collect = Stage(
            "rmb-collect",
            [
                entry.rmb_env_name,
                f"--episodes={args.episodes}",
                f"--out={rmb}",
                "--cameras",
                *CAMERAS["with touch"],
                "--image-size",
                str(width),
                str(height),
                "--no-depth",
                "--success-only",
                f"--random-shift={args.random_shift}",
                "--workers=2",
            ],
        )
        timings["collect"] = _run_all([(collect, args.out / "rmb.log")])
    converts, trains, evals = [], [], []
    for name, out in runs.items():
        env_args = [
            f"--env.type={entry.lerobot_type}",
            f"--env.cameras={_list(CAMERAS[name])}",
            f"--env.image_width={width}",
            f"--env.image_height={height}",
        ]
        repo_id = f"local/{entry.task}_{out.name}"
        converts.append(
            (
                Stage(
                    "rmb-convert",
                    [
                        "to-lerobot",
                        str(rmb),
                        f"--repo-id={repo_id}",
                        f"--output={out / 'dataset'}",
                        "--camera-names",
                        *CAMERAS[name],
                    ],
                ),
                out / "dataset.log",
            )
        )
        for seed in seeds:
            train_dir = out / f"train{suffix(seed)}"
            stage = act_train_stage(
                repo_id,
                out / "dataset",
                env_args,
                train_dir,
                steps=args.steps,
                batch_size=args.batch_size,
                seed=seed,
                log_every=max(1, args.steps // 10),
                num_workers=args.num_workers,
            )
            # Only the device (and, if asked, intermediate checkpoints) differ from the recipe.
            replace = {"--policy.device=cpu": f"--policy.device={args.device}"}
            if args.save_freq:
                replace[f"--save_freq={args.steps}"] = f"--save_freq={args.save_freq}"
            trains.append(
                (
                    Stage(stage.name, [replace.get(a, a) for a in stage.args]),
                    train_dir.with_suffix(".log"),
                )
            )
            eval_dir = out / f"eval{suffix(seed)}"
            evals.append(
                (
                    Stage(
                        "lerobot-eval",
                        [
                            f"--policy.path={train_dir / 'checkpoints/last/pretrained_model'}",
                            "--policy.device=cpu",
                            *env_args,
                            f"--env.random_shift={args.random_shift}",
                            f"--eval.n_episodes={args.eval_episodes}",
                            "--eval.batch_size=1",
                            f"--seed={eval_seed}",  # unseen seeds: unseen shifts, worlds drawn
                            f"--output_dir={eval_dir}",
                        ],
                    ),
                    eval_dir.with_suffix(".log"),
                )
            )
    if do["collect"]:
        timings["convert"] = _run_all(converts, args.jobs)
    if do["train"]:
        for _, out in runs.items():
            if not (out / "dataset" / "meta" / "info.json").exists():
                raise SystemExit(f"tactile_ablation: no {out / 'dataset'} (--stage collect)")
        for _, log in trains:
            train_dir = log.with_suffix("")
            if train_dir.exists():  # lerobot-train refuses an existing output directory
                shutil.rmtree(train_dir)
        timings["train"] = _run_all(trains, args.jobs)
    if do["eval"]:
        for _, log in evals:
            eval_dir = log.with_suffix("")
            if eval_dir.exists():
                shutil.rmtree(eval_dir)
        timings["eval"] = _run_all(evals, args.jobs)
        summarize(args, entry.rmb_env_name, runs, seeds, eval_seed, suffix)
    print("time: " + ", ".join(f"{k} {v / 60:.1f} min" for k, v in timings.items()))
    return 0


def summarize(args, env_name, runs, seeds, eval_seed, suffix) -> None:
    """Print and save success per policy and seed, final losses, and a pooled interval per arm."""
    print(
        f"\n{env_name}: {args.episodes} demos (shift {args.random_shift} m), ACT "
        f"{args.steps} steps x batch {args.batch_size} on {args.device}, seeds "
        f"{' '.join(map(str, seeds))}; {args.eval_episodes} eval episodes each (seeds from "
        f"{eval_seed})"
    )
    print("| policy input | training seed | success | last logged training loss |")
    print("|---|---:|---:|---:|")
    summary = {"steps": args.steps, "batch_size": args.batch_size, "device": args.device}
    summary["eval_seed"], summary["arms"] = eval_seed, {}
    for name, out in runs.items():
        arm = {"per_seed": {}}
        total_s = total_n = 0
        for seed in seeds:
            info = json.loads((out / f"eval{suffix(seed)}" / "eval_info.json").read_text())
            overall = info["overall"]
            n = int(overall["n_episodes"])
            s = round(overall["pc_success"] * n / 100)
            logged = final_loss(out / f"train{suffix(seed)}.log")
            arm["per_seed"][seed] = {"success": s, "n": n, "last_logged_loss": logged}
            total_s, total_n = total_s + s, total_n + n
            loss_txt = f"{logged[1]:.3f} (step {logged[0]})" if logged else "?"
            print(
                f"| {name} ({', '.join(CAMERAS[name])}) | {seed} | {s}/{n} ({100 * s / n:.0f} %) "
                f"| {loss_txt} |"
            )
        low, high = wilson(total_s, total_n)
        arm.update(success=total_s, n=total_n, wilson95=[low, high])
        summary["arms"][name] = arm
    for name, arm in summary["arms"].items():
        low, high = arm["wilson95"]
        print(
            f"{name}: {arm['success']}/{arm['n']} pooled, Wilson 95 % "
            f"[{100 * low:.0f} %, {100 * high:.0f} %]"
        )
    (args.out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")


if __name__ == "__main__":
    sys.exit(main())
