"""How each policy is trained on a CPU, and the four commands of one benchmark cell.

A *recipe* is a policy's LeRobot options, its inputs (RGB cameras, or depth) and its training
budget (steps x batch), sized so that runs cost roughly the same CPU time on a 2-core machine.
The command builders return :class:`~rmb_lerobot.cli.quickstart.Stage` objects: the unmodified
command-line tools (``rmb-collect``, ``rmb-convert to-lerobot``, ``lerobot-train``,
``lerobot-eval``) with their arguments, so every command can be printed and re-run by hand.
``rmb-benchmark`` and ``benchmarks/learning.py`` both build their commands here.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rmb_lerobot.cli.quickstart import ACT_CPU_ARGS, Stage
from rmb_lerobot.envs.registry import entry_for


@dataclass(frozen=True)
class Recipe:
    """One policy's training recipe.

    ``cameras`` None means the benchmark's cameras; ``depth`` trains on those cameras' depth
    images (``rmb-convert --depth``, ``--env.depth=true``) as DP3 and Flow Policy need.
    """

    policy_type: str
    policy_args: tuple[str, ...] = ()
    steps: int = 1000
    batch_size: int = 16
    cameras: tuple[str, ...] | None = None
    depth: bool = False


# Diffusion Policy sized for a CPU: LeRobot's defaults (a 278 M-parameter U-Net, 100 DDPM
# denoising steps per query, ~34 s per action chunk on one thread: benchmarks/RESULTS.md) are for
# a GPU. No pretrained backbone (nothing is downloaded; group norm then replaces batch norm),
# a 16-step horizon for RMB's ~50-step episodes, a smaller U-Net and 10 DDIM steps per query:
# about 1 CPU second per training step at batch 8 with two 64x64 cameras (ACT: 0.53, MLP at
# batch 16: 0.5, SARNN at batch 8 of 21-frame windows: 3.9 (10-frame windows, the recipe's: ~1.2);
# measured on Cloth, 2 loaded cores).
DIFFUSION_CPU_ARGS = (
    "--policy.pretrained_backbone_weights=null",
    "--policy.use_group_norm=true",
    "--policy.horizon=16",
    "--policy.n_action_steps=8",
    "--policy.drop_n_last_frames=7",  # horizon - n_action_steps - n_obs_steps + 1
    "--policy.down_dims=[128,256,512]",
    "--policy.noise_scheduler_type=DDIM",
    "--policy.num_inference_steps=10",
    "--policy.scheduler_warmup_steps=100",  # LeRobot's 500 is most of a CPU-sized run
    # Predict the clean action chunk, not the noise (DP3's choice): at 800 x 8 on Insert the
    # noise-prediction loss was still 0.083 and 0/12 episodes succeeded; predicting the sample
    # reached loss 0.001 and 12/12 at the same budget (benchmarks/RESULTS.md, 2026-11-25).
    "--policy.prediction_type=sample",
)

RECIPES: dict[str, Recipe] = {
    "act": Recipe("act", ACT_CPU_ARGS),  # the main job's ACT (rmb-quickstart)
    "mlp": Recipe("mlp", ("--policy.optimizer_lr=1e-4",)),
    "diffusion": Recipe("diffusion", DIFFUSION_CPU_ARGS),
    # A SARNN sample is a window of sequence_length steps, frame_skip 6 frames apart. 9 steps
    # cover Insert's longest demo (55 frames); the default 20 made windows 83 % padding. lr 1e-3
    # fits one demo ~7x faster than 1e-4 (open-loop error 0.0072 rad after 120 steps vs 0.026
    # after 300); 200 x 8 windows of 20 (0.7 epoch) gave 0 % on Insert, 500 x 8 of 9 gave 3 of
    # 6 worlds (2026-11-24 diagnosis, benchmarks/RESULTS.md).
    "sarnn": Recipe(
        "sarnn",
        ("--policy.sequence_length=9", "--policy.optimizer_lr=1e-3"),
        steps=1500,
        batch_size=8,
    ),
    # DP3 samples from the EMA of its weights (the plugin's default, as RMB); its 500 warm-up
    # steps (DP3's, for 3000 epochs on a GPU) would be half of a CPU-sized run.
    "dp3": Recipe("dp3", ("--policy.scheduler_warmup_steps=100",), cameras=("front",), depth=True),
    "flow_policy": Recipe("flow_policy", cameras=("front",), depth=True),  # DP3's inputs
    # ManiFlow at its CPU size (the paper's 192 M parameters are for a GPU).
    "maniflow": Recipe(
        "maniflow",
        (
            "--policy.n_layer=2",
            "--policy.n_head=4",
            "--policy.n_emb=64",
            "--policy.resnet_width=16",
        ),
    ),
}


def cli_value(value: Any) -> str:
    """A value in draccus' command-line syntax: ``null``, ``true``, ``[64,128]``, ``1e-4``."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, list | tuple):
        return "[" + ",".join(cli_value(v) for v in value) + "]"
    if isinstance(value, Mapping):
        raise ValueError(f"nested option values are not supported: {value!r}")
    return str(value)


def policy_option_args(options: Mapping[str, Any]) -> tuple[str, ...]:
    """``{"chunk_size": 20}`` -> ``("--policy.chunk_size=20",)``."""
    return tuple(f"--policy.{key}={cli_value(value)}" for key, value in options.items())


@dataclass(frozen=True)
class EnvInputs:
    """What the env shows the policy: task, cameras, image size, depth, step limit, and what
    its actions mean (``action_mode``: joint, eef_abs or eef_rel; only a non-joint mode is
    passed, as ``--env.action_mode``)."""

    task: str
    cameras: tuple[str, ...]
    image_size: tuple[int, int] = (64, 64)  # width, height
    depth: bool = False
    episode_length: int | None = None
    action_mode: str = "joint"

    def args(self) -> list[str]:
        width, height = self.image_size
        args = [
            f"--env.type={entry_for(self.task).lerobot_type}",
            f"--env.cameras=[{','.join(self.cameras)}]",
            f"--env.image_width={width}",
            f"--env.image_height={height}",
        ]
        if self.depth:
            args.append("--env.depth=true")
        if self.episode_length:
            args.append(f"--env.episode_length={self.episode_length}")
        if self.action_mode != "joint":
            args.append(f"--env.action_mode={self.action_mode}")
        return args


def collect_stage(
    task: str,
    out: Path,
    episodes: int,
    cameras: Sequence[str],
    image_size: tuple[int, int],
    *,
    depth: bool = False,
    workers: int = 1,
    seed: int = 0,
    overwrite: bool = False,
    extra: Sequence[str] = (),
) -> Stage:
    """``rmb-collect``: successful scripted-expert demos, worlds cycled 0..5."""
    width, height = image_size
    return Stage(
        "rmb-collect",
        [
            entry_for(task).rmb_env_name,
            f"--episodes={episodes}",
            f"--out={out}",
            "--cameras",
            *cameras,
            "--image-size",
            str(width),
            str(height),
            *([] if depth else ["--no-depth"]),
            "--success-only",
            f"--workers={workers}",
            f"--seed={seed}",
            *(["--overwrite"] if overwrite else []),
            *extra,
        ],
    )


def collect_covers(recorded: Sequence[str], needed: Sequence[str]) -> bool:
    """Whether demos collected by the ``rmb-collect`` command ``recorded`` serve a grid that
    needs ``needed``: the same command but for at least as many episodes, a superset of the
    cameras, and depth if needed (the first N episodes of a collection do not depend on how many
    follow, nor on which cameras are rendered)."""

    def split(argv: Sequence[str]) -> tuple[list[str], set[str], bool, int] | None:
        argv = list(argv)
        try:
            start, end = argv.index("--cameras") + 1, argv.index("--image-size")
        except ValueError:
            return None
        episodes = [a for a in argv if a.startswith("--episodes=")]
        if len(episodes) != 1:
            return None
        rest = [a for a in argv[:start] + argv[end:] if a not in (*episodes, "--no-depth")]
        return rest, set(argv[start:end]), "--no-depth" not in argv, int(episodes[0].split("=")[1])

    old, new = split(recorded), split(needed)
    if old is None or new is None:
        return False
    return old[0] == new[0] and old[1] >= new[1] and (old[2] or not new[2]) and old[3] >= new[3]


def convert_stage(
    sources: Sequence[Path],
    output: Path,
    repo_id: str,
    *,
    cameras: Sequence[str] | None = None,
    depth: bool = False,
    video_codec: str | None = None,
    extra: Sequence[str] = (),
) -> Stage:
    """``rmb-convert to-lerobot``: episodes (or directories of them) -> one LeRobotDataset."""
    return Stage(
        "rmb-convert",
        [
            "to-lerobot",
            *map(str, sources),
            f"--output={output}",
            f"--repo-id={repo_id}",
            *(["--depth"] if depth else []),
            *(["--camera-names", *cameras] if cameras else []),
            *([f"--video-codec={video_codec}"] if video_codec else []),
            *extra,
        ],
    )


@dataclass(frozen=True)
class TrainSpec:
    """One ``lerobot-train`` run: policy, budget, dataset, env inputs, where it writes."""

    policy_type: str
    policy_args: tuple[str, ...]
    steps: int
    batch_size: int
    dataset: Path
    repo_id: str
    env: EnvInputs
    output_dir: Path
    seed: int = 1
    device: str = "cpu"
    num_workers: int = 0
    eval_freq: int = 0  # lerobot-train's periodic env evaluation (learning curves); 0: off
    eval_episodes: int = 1
    extra: tuple[str, ...] = field(default=())


def train_stage(spec: TrainSpec) -> Stage:
    """The unmodified ``lerobot-train`` for ``spec``; saves only the final checkpoint."""
    periodic = (
        [
            f"--env_eval_freq={spec.eval_freq}",
            f"--eval.n_episodes={spec.eval_episodes}",
            "--eval.batch_size=1",
            "--eval.use_async_envs=false",
        ]
        if spec.eval_freq
        else ["--env_eval_freq=0"]
    )
    return Stage(
        "lerobot-train",
        [
            f"--dataset.repo_id={spec.repo_id}",
            f"--dataset.root={spec.dataset}",
            f"--policy.type={spec.policy_type}",
            *spec.policy_args,
            f"--policy.device={spec.device}",
            "--policy.push_to_hub=false",
            *spec.env.args(),
            *periodic,
            f"--steps={spec.steps}",
            f"--batch_size={spec.batch_size}",
            f"--save_freq={spec.steps}",
            f"--log_freq={max(1, spec.steps // 20)}",
            f"--num_workers={spec.num_workers}",
            f"--seed={spec.seed}",
            f"--output_dir={spec.output_dir}",
            "--wandb.enable=false",
            *spec.extra,
        ],
    )


def checkpoint_of(train_output_dir: Path) -> Path:
    """The final policy ``lerobot-train`` leaves in its output directory."""
    return train_output_dir / "checkpoints" / "last" / "pretrained_model"


def eval_stage(
    checkpoint: Path,
    env: EnvInputs,
    world: int,
    episodes: int,
    seed: int,
    output_dir: Path,
    *,
    device: str = "cpu",
    random_shift: float = 0.0,
) -> Stage:
    """The unmodified ``lerobot-eval``: ``episodes`` episodes, all in world ``world``, each with
    a uniform object shift of up to ``random_shift`` metres drawn from its seed (0: the world's
    own placement)."""
    return Stage(
        "lerobot-eval",
        [
            f"--policy.path={checkpoint}",
            f"--policy.device={device}",
            *env.args(),
            f"--env.world_idx={world}",
            *([f"--env.random_shift={random_shift}"] if random_shift else []),
            f"--eval.n_episodes={episodes}",
            "--eval.batch_size=1",
            "--eval.use_async_envs=false",
            f"--seed={seed}",
            f"--output_dir={output_dir}",
        ],
    )
