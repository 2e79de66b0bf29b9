"""``rmb-quickstart``: the README's main job, the real pipeline end to end on a CPU.

1. ``rmb-collect``: scripted-expert demonstrations in an RMB simulation env, as RMB episodes;
2. ``rmb-convert to-lerobot``: the episodes become one LeRobotDataset v3;
3. ``lerobot-train``: LeRobot's ACT (no pretrained backbone, small images) on that dataset,
   with ``--env.type=rmb_ur5e_<task>`` so the policy's inputs are checked against the env;
4. ``lerobot-eval``: the trained checkpoint in the same env; success rate and videos; then again
   with the objects shifted at random (``--unseen-shift``), placements no demo showed.

Every stage is the unmodified command-line tool, run as a subprocess and printed first so it can
be re-run by hand; the defaults fit in about 15 minutes on a 2-core CPU.
"""

from __future__ import annotations

import argparse
import json
import os
import shlex
import shutil
import subprocess
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from rmb_lerobot.cli.help import DefaultsHelpFormatter, first_line
from rmb_lerobot.envs.registry import entry_for
from rmb_lerobot.optim import fused_adamw_args

TORCH_THREADS = 1  # per stage process, unless OMP_NUM_THREADS is set

# What a run writes into --out: one folder per stage, and the marker that says the directory is
# this tool's (so a later run may replace those folders, and only those).
STAGE_DIRS = ("rmb", "dataset", "train", "eval", "eval_unseen")
MARKER = ".rmb-quickstart"

# The LeRobot entry points, by their console-script names (what the printed commands show).
LEROBOT_MODULES = {
    "lerobot-train": "lerobot.scripts.lerobot_train",
    "lerobot-eval": "lerobot.scripts.lerobot_eval",
}


# LeRobot's ACT sized for a CPU and for RMB's short episodes (about 50 steps for Insert): no
# pretrained backbone (nothing is downloaded), a smaller transformer, 20-step action chunks
# replanned every 10 steps, and a learning rate for short runs (ACT's default 1e-5 is for
# 100k-step trainings).
ACT_LR = 1e-4
ACT_WEIGHT_DECAY = 1e-4  # ACT's own default (ACTConfig.optimizer_weight_decay)
ACT_CPU_ARGS = (
    "--policy.pretrained_backbone_weights=null",
    "--policy.chunk_size=20",
    "--policy.n_action_steps=10",
    "--policy.dim_model=256",
    "--policy.dim_feedforward=1024",
    "--policy.n_encoder_layers=2",
    f"--policy.optimizer_lr={ACT_LR:g}",
)
# ACT's optimizer preset (AdamW at that lr and weight decay, no scheduler) with PyTorch's fused
# AdamW kernel: the same update in 0.82x the CPU per step (rmb_lerobot.optim;
# benchmarks/optimizer_step.py). Not the quick start's default: its three runs so far succeeded
# less often (10/12 at 500 steps, 8/12 at 1000) than LeRobot's AdamW's (12/12 at 500 and at
# 1000), which 12-episode evaluations of single seeds cannot tell from chance (RESULTS.md
# "Main job").
ACT_OPTIMIZER_ARGS = fused_adamw_args(lr=ACT_LR, weight_decay=ACT_WEIGHT_DECAY)


@dataclass(frozen=True)
class Stage:
    """One command of the pipeline: its console-script name and its arguments."""

    name: str
    args: list[str]

    def argv(self) -> list[str]:
        """The command to run, with this interpreter (so the venv is used even if not active)."""
        if self.name in LEROBOT_MODULES:
            return [sys.executable, "-m", LEROBOT_MODULES[self.name], *self.args]
        script = Path(sys.executable).with_name(self.name)
        return [str(script) if script.exists() else self.name, *self.args]

    def __str__(self) -> str:
        return shlex.join([self.name, *self.args])


def _list(values: Sequence[str]) -> str:
    """A list in draccus' command-line syntax: ``[front,hand]``."""
    return "[" + ",".join(values) + "]"


def act_train_stage(
    repo_id: str,
    dataset: Path,
    env_args: Sequence[str],
    out: Path,
    *,
    steps: int,
    batch_size: int,
    seed: int,
    log_every: int,
    num_workers: int,
    optimizer_args: Sequence[str] = (),
) -> Stage:
    """``lerobot-train`` of LeRobot's ACT with the CPU recipe (:data:`ACT_CPU_ARGS`) on a local
    dataset, its env type given by ``env_args``, evaluated afterwards by ``lerobot-eval``.

    Args:
        repo_id: The dataset's id.
        dataset: The dataset's root.
        env_args: ``--env.*`` arguments (type, cameras, image size).
        out: LeRobot's output directory (checkpoints).
        steps: Training steps (one checkpoint, at the end).
        batch_size: Samples per step.
        seed: Training seed.
        log_every: Steps between log lines.
        num_workers: Data loader workers.
        optimizer_args: ``lerobot-train`` optimizer arguments replacing ACT's preset, e.g.
            :data:`ACT_OPTIMIZER_ARGS` (none: LeRobot's AdamW preset).

    Returns:
        The stage.
    """
    return Stage(
        "lerobot-train",
        [
            f"--dataset.repo_id={repo_id}",
            f"--dataset.root={dataset}",
            "--policy.type=act",
            *ACT_CPU_ARGS,
            *optimizer_args,
            "--policy.device=cpu",
            "--policy.push_to_hub=false",
            *env_args,
            "--env_eval_freq=0",  # evaluated once afterwards, with lerobot-eval
            f"--steps={steps}",
            f"--batch_size={batch_size}",
            f"--save_freq={steps}",
            f"--log_freq={log_every}",
            f"--num_workers={num_workers}",
            f"--seed={seed}",
            f"--output_dir={out}",
            "--wandb.enable=false",
        ],
    )


def pipeline(args: argparse.Namespace) -> list[Stage]:
    """The four commands of the main job, for the options given."""
    entry = entry_for(args.env)
    out: Path = args.out
    width, height = args.image_size
    repo_id = f"local/rmb_{entry.task}_quickstart"
    env_args = [
        f"--env.type={entry.lerobot_type}",
        f"--env.cameras={_list(args.cameras)}",
        f"--env.image_width={width}",
        f"--env.image_height={height}",
    ]
    collect = Stage(
        "rmb-collect",
        [
            entry.rmb_env_name,
            f"--episodes={args.episodes}",
            f"--out={out / 'rmb'}",
            "--cameras",
            *args.cameras,
            "--image-size",
            str(width),
            str(height),
            "--no-depth",
            "--success-only",
            f"--workers={args.workers}",
            "--overwrite",
        ],
    )
    convert = Stage(
        "rmb-convert",
        [
            "to-lerobot",
            str(out / "rmb"),
            f"--repo-id={repo_id}",
            f"--output={out / 'dataset'}",
            # One process: a second one costs more than it saves on the demo's 30 short
            # episodes (each worker imports LeRobot; the shards are merged afterwards): 33 vs
            # 65 CPU s (benchmarks/RESULTS.md "Main job").
            "--workers=1",
            # Only what ACT reads: LeRobot's loader reads every column of a sampled row
            # (0.62x CPU per sample; benchmarks/RESULTS.md "Training data path").
            "--no-extra-keys",
            "--overwrite",
        ],
    )
    train = act_train_stage(
        repo_id,
        out / "dataset",
        env_args,
        out / "train",
        steps=args.steps,
        batch_size=args.batch_size,
        seed=args.seed,
        log_every=max(1, args.steps // 20),
        # One spawned worker keeps up with ACT's update on 2 cores: after its start-up (the first
        # log window's data_s) data_s stays a few % of updt_s. RGB stays AV1 video: image
        # features (--image-features) cost ~2x loader CPU per sample with action chunks in
        # LeRobot 0.6.1 (benchmarks/data_path.py, RESULTS.md "Training data path").
        num_workers=1,
        optimizer_args=ACT_OPTIMIZER_ARGS if args.fused_adamw else (),
    )
    evaluate = Stage(
        "lerobot-eval",
        [
            f"--policy.path={checkpoint_dir(out)}",
            "--policy.device=cpu",
            *env_args,
            *([f"--env.episode_length={args.episode_length}"] if args.episode_length else []),
            f"--eval.n_episodes={args.eval_episodes}",
            f"--eval.batch_size={min(args.eval_episodes, args.workers)}",
            f"--eval.use_async_envs={'true' if args.workers > 1 else 'false'}",
            f"--seed={args.seed + 1000}",  # no shift: the worlds the demos showed ("seen")
            f"--output_dir={out / 'eval'}",
        ],
    )
    if not args.unseen_shift:
        return [collect, convert, train, evaluate]
    # The demos replay each world's own placement: the same evaluation with the objects
    # shifted at random shows how the policy does on placements it has never seen.
    unseen = Stage(
        "lerobot-eval",
        [
            *[a for a in evaluate.args if not a.startswith(("--seed=", "--output_dir="))],
            f"--env.random_shift={args.unseen_shift}",
            f"--seed={args.seed + 2000}",
            f"--output_dir={out / 'eval_unseen'}",
        ],
    )
    return [collect, convert, train, evaluate, unseen]


def checkpoint_dir(out: Path) -> Path:
    """Where ``lerobot-train`` leaves the final policy (config, weights, processors)."""
    return out / "train" / "checkpoints" / "last" / "pretrained_model"


def run(stage: Stage, index: int, total: int) -> float:
    """Run one stage with its output shown live; stop the pipeline if it fails."""
    print(f"\n=== [{index}/{total}] {stage}\n", flush=True)
    env = {**os.environ, "HF_HUB_OFFLINE": "1", "WANDB_MODE": "disabled"}
    # One torch thread per process: training already runs next to a video-decoding data
    # worker, and OpenMP threads that outnumber the free cores slow down many-fold.
    env.setdefault("OMP_NUM_THREADS", str(TORCH_THREADS))
    start = time.perf_counter()
    result = subprocess.run(stage.argv(), env=env, check=False)
    if result.returncode != 0:
        raise SystemExit(f"rmb-quickstart: {stage.name} failed (exit {result.returncode})")
    return time.perf_counter() - start


def read_eval(info_path: Path) -> tuple[dict, list[bool]]:
    """``lerobot-eval``'s overall numbers and per-episode successes from its eval_info.json."""
    try:
        info = json.loads(info_path.read_text())
        overall = info["overall"]
    except (OSError, KeyError, json.JSONDecodeError) as error:
        raise SystemExit(f"rmb-quickstart: no evaluation result in {info_path}: {error}") from None
    successes = [s for task in info.get("per_task", []) for s in task["metrics"]["successes"]]
    return overall, successes


def report(out: Path, timings: dict[str, float], unseen_shift: float = 0.0) -> list[str]:
    """The summary: success rate (on the demos' placements and, with ``unseen_shift``, on
    placements shifted up to that many metres), where the dataset, policy and videos are."""
    info_path = out / "eval" / "eval_info.json"
    overall, successes = read_eval(info_path)
    videos = [Path(p) for p in overall.get("video_paths", [])]
    lines = [
        "",
        f"success rate: {overall['pc_success']:.1f} % ({sum(successes)}/{len(successes)} "
        f"episodes), mean return {overall['avg_sum_reward']:.2f}",
    ]
    if unseen_shift:
        unseen, unseen_successes = read_eval(out / "eval_unseen" / "eval_info.json")
        lines.append(
            f"unseen:       {unseen['pc_success']:.1f} % ({sum(unseen_successes)}/"
            f"{len(unseen_successes)} episodes) with objects shifted up to "
            f"{100 * unseen_shift:g} cm (the demos: each world's own placement)"
        )
    lines += [
        f"dataset:      {(out / 'dataset').absolute()}",
        f"policy:       {checkpoint_dir(out).absolute()}",
        f"eval:         {info_path.absolute()}",
    ]
    if videos:
        lines.append(f"eval videos:  {videos[0].parent.absolute()} ({len(videos)} files)")
    timing = ", ".join(f"{name} {seconds:.0f} s" for name, seconds in timings.items())
    lines.append(f"time:         {timing}; total {sum(timings.values()) / 60:.1f} min")
    return lines


def build_parser() -> argparse.ArgumentParser:
    """The command line of ``rmb-quickstart``."""
    parser = argparse.ArgumentParser(
        prog="rmb-quickstart",
        description=first_line(__doc__),
        formatter_class=DefaultsHelpFormatter,
        epilog=f"--out holds one folder per stage ({', '.join(f'{s}/' for s in STAGE_DIRS)}) and "
        f"a {MARKER} marker. A run into a directory made by an earlier rmb-quickstart replaces "
        "those stage folders only; a non-empty directory it did not make is refused unless "
        "--reuse-out is given, and nothing it did not create is ever deleted.",
    )
    parser.add_argument(
        "--out",
        type=Path,
        default=Path("outputs/quickstart"),
        help="output directory: demos, dataset, trained policy and evaluation, one folder each",
    )
    parser.add_argument(
        "--reuse-out",
        action="store_true",
        help="use a non-empty --out that rmb-quickstart did not make (its files stay; refused if "
        "it already holds a stage folder)",
    )
    parser.add_argument("--env", default="insert", help="RMB env (short name, RMB name, type)")
    parser.add_argument("--episodes", type=int, default=30, help="demonstrations to collect")
    parser.add_argument(
        "--cameras", nargs="+", default=["front", "hand"], help="cameras recorded and trained on"
    )
    parser.add_argument(
        "--image-size",
        nargs=2,
        type=int,
        default=[64, 64],
        metavar=("W", "H"),
        help="image width and height of the demos, the policy and the evaluation",
    )
    parser.add_argument("--steps", type=int, default=1000, help="training steps")
    parser.add_argument("--batch-size", type=int, default=8, help="training batch size")
    parser.add_argument(
        "--fused-adamw",
        action="store_true",
        help="train with --optimizer.type=adamw_fused (ACT's AdamW preset in PyTorch's fused "
        "kernel, 0.82x the CPU per step) instead of LeRobot's preset",
    )
    parser.add_argument(
        "--eval-episodes", type=int, default=12, help="evaluation episodes (lerobot-eval)"
    )
    parser.add_argument(
        "--unseen-shift",
        type=float,
        default=0.02,
        help="evaluate again with objects shifted at random by up to this many metres, "
        "placements no demo showed (0: skip)",
    )
    parser.add_argument(
        "--episode-length",
        type=int,
        default=None,
        help="eval step limit (None: the task's own)",
    )
    parser.add_argument("--workers", type=int, default=2, help="processes for collect and eval")
    parser.add_argument(
        "--seed", type=int, default=1, help="training seed (evaluation uses seed + 1000)"
    )
    return parser


def parse_args(argv: Sequence[str] | None) -> argparse.Namespace:
    """The options of ``rmb-quickstart``, parsed from ``argv`` (default: ``sys.argv``)."""
    return build_parser().parse_args(argv)


class OutDirError(ValueError):
    """``--out`` cannot be used without deleting or mixing in files this tool did not create."""


def prepare_out(out: Path, *, reuse: bool = False) -> None:
    """Make ``out`` ready for a fresh run, deleting only what an earlier run of this tool made.

    A new or empty directory gets the :data:`MARKER` file. A directory with the marker (an
    earlier ``rmb-quickstart``'s) loses its stage folders (:data:`STAGE_DIRS`: LeRobot refuses
    an existing output_dir) and keeps anything else. A non-empty directory without it is refused
    unless ``reuse``; then it is used as it is, provided none of the stage folders is there.

    Args:
        out: The ``--out`` directory.
        reuse: ``--reuse-out``: accept a non-empty directory this tool did not make.

    Raises:
        OutDirError: ``out`` is a file, or a non-empty directory not made by this tool (without
            ``reuse``, or with a stage folder in it).
    """
    if out.exists() and not out.is_dir():
        raise OutDirError(f"--out {out}: is a file, expected a directory")
    marked = (out / MARKER).is_file()
    if out.is_dir() and not marked and any(out.iterdir()):
        if not reuse:
            raise OutDirError(
                f"--out {out}: not empty and not made by rmb-quickstart (no {MARKER} in it); "
                "choose a new or empty directory, or pass --reuse-out to use it (nothing in it "
                "is deleted)"
            )
        clashes = [name for name in STAGE_DIRS if (out / name).exists()]
        if clashes:
            raise OutDirError(
                f"--out {out}: already holds {', '.join(clashes)}, which rmb-quickstart did not "
                "make and would have to replace; choose another directory"
            )
    if marked:
        for name in STAGE_DIRS:
            if (out / name).is_dir():
                shutil.rmtree(out / name)
    out.mkdir(parents=True, exist_ok=True)
    (out / MARKER).write_text(
        "Made by rmb-quickstart: a later run here replaces the folders "
        f"{', '.join(STAGE_DIRS)} and nothing else.\n"
    )


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    stages = pipeline(args)  # an unknown env is refused before --out is touched
    try:
        prepare_out(args.out, reuse=args.reuse_out)
    except OutDirError as error:
        parser.error(str(error))
    timings = {}
    for index, stage in enumerate(stages, start=1):
        # Both evaluations count as lerobot-eval.
        timings[stage.name] = timings.get(stage.name, 0.0) + run(stage, index, len(stages))
    print("\n".join(report(args.out, timings, args.unseen_shift)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
