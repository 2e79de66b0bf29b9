r"""What SART augmentation buys: one policy trained from N demos vs N demos + augmentation.

Usage::

    .venv/bin/python benchmarks/augmentation.py [--env insert] [--policy mlp] [--world 2]
        [--samples 16] [--radius 0.04] [--duration 1.0] [--steps 300] [--batch-size 16]
        [--eval-episodes 3] [--out outputs/augmentation]

    # the paper's setting (issue 28): images-only ACT on the hand camera, relative eef actions,
    # 3 demos with their own 2 cm object shifts, evaluated on unseen 2 cm shifts in their world
    .venv/bin/python benchmarks/augmentation.py --policy act --cameras hand --images-only \
        --action-mode eef_rel --demos 3 --demo-shift 0.02 --eval-shift 0.02 \
        --steps 1000 --batch-size 8 --eval-episodes 12 --out /tmp/sart_paper

Defaults (issue 14's study): one scripted demonstration in world ``--world`` (front + hand
cameras 64x64, as ``benchmarks/learning.py``), ``rmb-augment --propose-regions`` around it (or
``--regions YAML``; ``--samples`` per region), two datasets (the demo alone; the demo + its
augmentations) converted with ``rmb-convert to-lerobot``, and the same policy recipe and
training budget on each (``learning.py``'s recipes and seed: unmodified ``lerobot-train``, one
torch thread, then ``lerobot-eval`` ``--eval-episodes`` times in each world 0..5 with unseen
seeds 1000+K). Joint state in, joint command out.

The paper's setting (options, any combination):

- ``--demos N --demo-shift S``: N demos in world ``--world``, each reset with its own seed
  (``--demo-seed`` + i) and so its own uniform object shift of up to S metres (one
  ``rmb-collect`` call, every episode checked to be a success); SART runs around each demo with
  that seed and shift (``rmb-augment --seed --random-shift``), so it restores the demo's scene.
- ``--cameras hand``: the cameras recorded, converted, trained on and evaluated.
- ``--images-only``: the policy's inputs are the cameras only, no ``observation.state``
  (ACT only). The converter always writes a state feature, so this is LeRobot's own
  ``--policy.input_features`` option of ``lerobot-train`` (LeRobot 0.6.1 unmodified: features
  given there are kept instead of the dataset's); the checkpoint keeps them for
  ``lerobot-eval``, which then ignores the env's ``agent_pos``.
- ``--action-mode eef_rel``: actions are ``command_eef_pose_rel`` + ``command_gripper_joint_pos``
  (the previous command's pose to this one's, as the env applies them) and the env runs
  ``--env.action_mode=eef_rel`` in evaluation.
- ``--eval-shift S``: evaluation in the demos' world only, every episode with an unseen uniform
  object shift of up to S metres (``--env.random_shift``), all ``--eval-episodes`` of a
  condition in one ``lerobot-eval`` call (seeds 1000+world onwards, checked to be disjoint from
  every seed a demo was reset with).

Prints the setting and a markdown table. Stages whose output exists are skipped, so an
interrupted run resumes.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import learning

from rmb_lerobot import find_episodes, open_episode
from rmb_lerobot import keys as K
from rmb_lerobot.benchmark.recipes import (
    EnvInputs,
    TrainSpec,
    checkpoint_of,
    eval_stage,
    train_stage,
)
from rmb_lerobot.cli.quickstart import Stage, run
from rmb_lerobot.envs.registry import entry_for
from rmb_lerobot.lerobot_names import image_key

CONDITIONS = ("demo", "demo+sart")
EVAL_SEED = 1000  # + world: lerobot-eval's first episode seed; episode k takes seed + k
MAX_ATTEMPTS = 5  # rmb-collect --success-only's tries per episode (seeds + attempt x episodes)
ACTION_KEYS = {
    "joint": (K.COMMAND_JOINT_POS,),
    "eef_rel": (K.COMMAND_EEF_POSE_REL, K.COMMAND_GRIPPER_JOINT_POS),
}


@dataclasses.dataclass(frozen=True)
class EvalTarget:
    """One ``lerobot-eval`` call: ``episodes`` episodes in ``world``, object shift up to
    ``shift`` metres (0: the world's own placement)."""

    world: int
    shift: float
    episodes: int

    @property
    def seed(self) -> int:
        return EVAL_SEED + self.world

    @property
    def seeds(self) -> range:
        return range(self.seed, self.seed + self.episodes)

    @property
    def label(self) -> str:
        return f"w{self.world}" + (f" ±{self.shift * 100:g} cm" if self.shift else "")

    @property
    def dirname(self) -> str:
        return f"world{self.world}" + (f"_shift{self.shift:g}" if self.shift else "")


def is_issue14_setting(args: argparse.Namespace) -> bool:
    """Whether every option of the paper's setting is at its default (issue 14's study)."""
    return (
        args.demos == 1
        and not args.demo_shift
        and tuple(args.cameras) == learning.CAMERAS
        and not args.images_only
        and args.action_mode == "joint"
        and args.eval_shift is None
    )


def condition_dir(args: argparse.Namespace, condition: str) -> Path:
    return args.out / condition.replace("+", "_")


def demo_dir(args: argparse.Namespace) -> Path:
    return args.out / "rmb" / "demo"


def demo_paths(args: argparse.Namespace) -> list[Path]:
    """The demos ``rmb-collect`` writes (episode i in world ``--world``)."""
    entry = entry_for(args.env)
    return [
        demo_dir(args) / f"{entry.rmb_env_name}_world{args.world}_{i:03d}.rmb"
        for i in range(args.demos)
    ]


def aug_dirs(args: argparse.Namespace) -> list[Path]:
    """Where each demo's augmentations go: ``rmb/sart`` for one unshifted demo (issue 14's
    layout), else one directory per demo (each holds its own ``regions.yaml``)."""
    root = args.out / "rmb" / "sart"
    if args.demos == 1 and not args.demo_shift:
        return [root]
    return [root / path.stem for path in demo_paths(args)]


def demo_reset_seeds(args: argparse.Namespace) -> set[int]:
    """Every seed a demo may have been reset with (and SART resets it with)."""
    if args.demo_shift:
        return {args.demo_seed + i for i in range(args.demos)}
    # --success-only: episode i's attempt a is reset with 0 + i + a x episodes.
    return {i + a * args.demos for i in range(args.demos) for a in range(MAX_ATTEMPTS)}


def collect_stage(args: argparse.Namespace) -> Stage:
    common = [
        entry_for(args.env).rmb_env_name,
        f"--episodes={args.demos}",
        f"--out={demo_dir(args)}",
        f"--world-idx={args.world}",
        "--cameras",
        *args.cameras,
        "--image-size",
        str(learning.SIZE),
        str(learning.SIZE),
        "--no-depth",
    ]
    if not args.demo_shift:
        return Stage("rmb-collect", [*common, "--success-only"])
    # No --success-only: a retry would be reset with another seed than --demo-seed + i, and
    # SART needs each demo's seed. check_demos() refuses failed demos instead.
    return Stage(
        "rmb-collect",
        [*common, f"--seed={args.demo_seed}", f"--random-shift={args.demo_shift}"],
    )


def augment_stage(args: argparse.Namespace, index: int) -> Stage:
    demo, out = demo_paths(args)[index], aug_dirs(args)[index]
    where = (
        [f"--regions={args.regions}"]
        if args.regions
        else ["--propose-regions", f"--radius={args.radius}"]
    )
    if args.demo_shift:
        seed = [f"--seed={args.demo_seed + index}", f"--random-shift={args.demo_shift}"]
    else:
        seed = ["--seed=0"]
    return Stage(
        "rmb-augment",
        [
            entry_for(args.env).rmb_env_name,
            str(demo),
            *where,
            f"--duration={args.duration}",
            f"--samples-per-region={args.samples}",
            f"--out={out}",
            *seed,
        ],
    )


def sources(args: argparse.Namespace) -> dict[str, list[Path]]:
    return {"demo": [demo_dir(args)], "demo+sart": [demo_dir(args), *aug_dirs(args)]}


def convert_stage(args: argparse.Namespace, condition: str) -> Stage:
    extra = []
    if not is_issue14_setting(args):
        extra = ["--action-keys", *ACTION_KEYS[args.action_mode], "--no-extra-keys"]
    return Stage(
        "rmb-convert",
        [
            "to-lerobot",
            *map(str, sources(args)[condition]),
            f"--output={condition_dir(args, condition) / 'rgb'}",
            "--repo-id=local/rgb",
            *extra,
        ],
    )


def check_demos(args: argparse.Namespace) -> None:
    """Every demo must be a success (it was collected without --success-only)."""
    for path in demo_paths(args):
        with open_episode(path) as episode:
            if float(episode[K.REWARD][-1]) <= 0:
                raise SystemExit(
                    f"{path.name} failed (reward 0 at its end); choose another --demo-seed "
                    f"(the demos are reset with seeds {args.demo_seed}..."
                    f"{args.demo_seed + args.demos - 1})"
                )


def run_data_stages(args: argparse.Namespace) -> None:
    """Collect, augment and convert, skipping the stages whose output exists."""
    stages: list[tuple[Stage, Path]] = [(collect_stage(args), demo_dir(args))]
    stages += [(augment_stage(args, i), out) for i, out in enumerate(aug_dirs(args))]
    stages += [(convert_stage(args, c), condition_dir(args, c) / "rgb") for c in CONDITIONS]
    todo = [stage for stage, done in stages if not done.exists()]
    for index, stage in enumerate(todo, start=1):
        run(stage, index, len(todo))
        if stage.name == "rmb-collect" and args.demo_shift:
            check_demos(args)


def eval_targets(args: argparse.Namespace) -> list[EvalTarget]:
    if args.eval_shift is None:
        return [EvalTarget(w, 0.0, args.eval_episodes) for w in learning.WORLDS]
    return [EvalTarget(args.world, args.eval_shift, args.eval_episodes)]


def check_seeds(args: argparse.Namespace) -> None:
    """Evaluation episodes in the demos' world must not replay a demo's reset seed."""
    demo_seeds = demo_reset_seeds(args)
    for target in eval_targets(args):
        if target.world == args.world and demo_seeds & set(target.seeds):
            raise SystemExit(
                f"evaluation seeds {target.seeds.start}..{target.seeds.stop - 1} overlap the "
                f"demos' reset seeds {sorted(demo_seeds)}; change --demo-seed"
            )


def env_inputs(args: argparse.Namespace) -> EnvInputs:
    size = (learning.SIZE, learning.SIZE)
    return EnvInputs(args.env, tuple(args.cameras), size, action_mode=args.action_mode)


def images_only_args(args: argparse.Namespace) -> tuple[str, ...]:
    """``--policy.input_features`` naming only the cameras (LeRobot keeps given features)."""
    if not args.images_only:
        return ()
    shape = [3, learning.SIZE, learning.SIZE]
    features = {image_key(cam): {"type": "VISUAL", "shape": shape} for cam in args.cameras}
    return (f"--policy.input_features={json.dumps(features)}",)


def train_dir(args: argparse.Namespace, condition: str) -> Path:
    return condition_dir(args, condition) / "train" / args.policy


def train_spec(args: argparse.Namespace, condition: str) -> TrainSpec:
    recipe = learning.RECIPES[args.policy]
    return TrainSpec(
        policy_type=recipe.policy_type,
        policy_args=(*recipe.policy_args, *images_only_args(args)),
        steps=args.steps or recipe.steps,
        batch_size=args.batch_size or recipe.batch_size,
        dataset=condition_dir(args, condition) / "rgb",
        repo_id="local/rgb",
        env=env_inputs(args),
        output_dir=train_dir(args, condition),
        seed=learning.SEED,
    )


def eval_stage_of(args: argparse.Namespace, condition: str, target: EvalTarget) -> Stage:
    return eval_stage(
        checkpoint_of(train_dir(args, condition)),
        env_inputs(args),
        target.world,
        target.episodes,
        target.seed,
        condition_dir(args, condition) / "eval" / args.policy / target.dirname,
        random_shift=target.shift,
    )


def train_and_evaluate(args: argparse.Namespace, condition: str) -> dict:
    """One condition: train (unless its checkpoint exists), then each evaluation."""
    train_s = None
    if not (train_dir(args, condition) / "checkpoints" / "last").exists():
        train_s = run(train_stage(train_spec(args, condition)), 1, 1)
    targets = eval_targets(args)
    success = []
    for index, target in enumerate(targets, start=1):
        out = condition_dir(args, condition) / "eval" / args.policy / target.dirname
        if not (out / "eval_info.json").exists():
            run(eval_stage_of(args, condition, target), index, len(targets))
        success.append(json.loads((out / "eval_info.json").read_text())["overall"]["pc_success"])
    return {"train_s": train_s, "success": success}


def frames(paths: list[Path]) -> int:
    total = 0
    for path in find_episodes(*paths):
        with open_episode(path) as episode:
            total += len(episode)
    return total


def episodes(paths: list[Path]) -> int:
    return len(find_episodes(*paths))


def table(results: dict[str, dict], args: argparse.Namespace) -> str:
    targets = eval_targets(args)
    header = "| training data | episodes | frames | train min | "
    header += " | ".join(t.label for t in targets) + " | all worlds |"
    lines = [header, "|---|---:|---:|---:|" + "---:|" * len(targets) + "---:|"]
    counts = not is_issue14_setting(args)  # successes as k/n too
    for condition, r in results.items():
        paths = sources(args)[condition]
        minutes = "-" if r["train_s"] is None else f"{r['train_s'] / 60:.1f}"
        cells = []
        for target, pc in zip(targets, r["success"], strict=True):
            wins = round(pc * target.episodes / 100)
            cells.append(f"{pc:.0f} %" + (f" ({wins}/{target.episodes})" if counts else ""))
        mean = sum(r["success"]) / len(r["success"])
        lines.append(
            f"| {condition} | {episodes(paths)} | {frames(paths)} | {minutes} | "
            f"{' | '.join(cells)} | **{mean:.0f} %** |"
        )
    return "\n".join(lines)


def setting(args: argparse.Namespace) -> str:
    """The run's setting, one item per line, for the results."""
    spec = train_spec(args, "demo")
    where = f"region of {args.regions}" if args.regions else f"proposed region ({args.radius} m)"
    seeds = sorted(demo_reset_seeds(args))
    shift = f"object shift up to {args.demo_shift} m each" if args.demo_shift else "no shift"
    evals = "; ".join(
        f"world {t.world}, shift up to {t.shift} m, {t.episodes} episodes, seeds "
        f"{t.seeds.start}..{t.seeds.stop - 1}"
        for t in eval_targets(args)
    )
    return "\n".join(
        [
            f"- policy: {args.policy} ({' '.join(spec.policy_args)})",
            f"- inputs: cameras {'+'.join(args.cameras)} {learning.SIZE}x{learning.SIZE}, "
            + ("images only (no observation.state)" if args.images_only else "+ joint state"),
            f"- actions: {args.action_mode} ({' + '.join(ACTION_KEYS[args.action_mode])})",
            f"- demos: {args.demos} in world {args.world}, {shift}; reset seeds "
            + (
                f"{seeds[0]}..{seeds[-1]}" if args.demo_shift else f"within {seeds[0]}..{seeds[-1]}"
            ),
            f"- SART: {args.samples} samples per {where}, {args.duration} s drives; "
            f"{episodes(aug_dirs(args))} augmented episodes",
            f"- budget: {spec.steps} steps x {spec.batch_size}, training seed {spec.seed}, "
            "one torch thread per run",
            f"- evaluation: {evals}",
        ]
    )


def parse_args() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--env", default="insert")
    parser.add_argument("--policy", default="mlp", choices=list(learning.RECIPES))
    parser.add_argument("--world", type=int, default=2, help="world of the demonstrations")
    parser.add_argument("--demos", type=int, default=1, help="demonstrations (each augmented)")
    parser.add_argument(
        "--demo-shift",
        type=float,
        default=0.0,
        help="metres: each demo's own uniform object shift, drawn from its seed (needed for "
        "--demos > 1: unshifted demos in one world are identical)",
    )
    parser.add_argument("--demo-seed", type=int, default=0, help="demo i is reset with this + i")
    parser.add_argument("--cameras", nargs="+", default=list(learning.CAMERAS))
    parser.add_argument(
        "--images-only", action="store_true", help="no observation.state input (ACT only)"
    )
    parser.add_argument("--action-mode", default="joint", choices=list(ACTION_KEYS))
    parser.add_argument(
        "--eval-shift",
        type=float,
        default=None,
        help="metres: evaluate in the demos' world only, each episode with an unseen object "
        "shift up to this (default: each world 0..5 as recorded)",
    )
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
    parser.add_argument(
        "--eval-episodes", type=int, default=3, help="per evaluated world (one lerobot-eval call)"
    )
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
    recipe = learning.RECIPES[args.policy]
    if recipe.depth or recipe.cameras:
        parser.error(f"{args.policy} trains on depth; this study converts RGB cameras only")
    if args.demos < 1 or (args.demos > 1 and not args.demo_shift):
        parser.error("--demos > 1 needs --demo-shift > 0 (unshifted demos are identical)")
    if args.images_only and args.policy != "act":
        parser.error(
            "--images-only: ACT only (LeRobot 0.6.1's Diffusion Policy always conditions on "
            "observation.state)"
        )
    return args


def main() -> None:
    args = parse_args()
    if args.policy_args:  # the same recipe for both runs, with these options added
        recipe = learning.RECIPES[args.policy]
        learning.RECIPES[args.policy] = dataclasses.replace(
            recipe, policy_args=(*recipe.policy_args, *args.policy_args)
        )
    check_seeds(args)

    os.environ.setdefault("OMP_NUM_THREADS", "1")
    start = time.perf_counter()
    run_data_stages(args)
    with ThreadPoolExecutor(args.parallel) as pool:
        outcomes = pool.map(lambda c: train_and_evaluate(args, c), CONDITIONS)
        results = dict(zip(CONDITIONS, outcomes, strict=True))
    recipe = learning.RECIPES[args.policy]
    where = f"region of {args.regions}" if args.regions else f"proposed region ({args.radius} m)"
    demos = f"{args.demos} demo{'s' * (args.demos != 1)}"
    print(
        f"\n{args.policy} ({args.steps} x {args.batch_size}, {learning.dataset_name(recipe)} "
        f"{'+'.join(args.cameras)} {learning.SIZE}x{learning.SIZE}) on "
        f"{entry_for(args.env).rmb_env_name}: {demos} in world {args.world} vs + "
        f"{args.samples} SART samples per {where}; {args.eval_episodes} eval episodes per world; "
        f"wall {(time.perf_counter() - start) / 60:.0f} min\n"
    )
    if args.policy_args:
        print("extra training options: " + " ".join(args.policy_args) + "\n")
    print(setting(args) + "\n")
    print(table(results, args))


if __name__ == "__main__":
    main()
