"""LeRobot's AdamW vs ``adamw_fused`` on the quick start's ACT: CPU seconds per training step.

Usage::

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/optimizer_step.py [--steps 30] [--rounds 3]

The quick start's ACT (no pretrained backbone, dim_model 256, feed-forward 1024, 2 encoder
layers, chunk 20, front + hand at 64x64, batch 8; ``rmb_lerobot.cli.quickstart``) on random
inputs, one torch thread: forward, backward, the optimizer step. Both optimizers are built from
their LeRobot configs with the same options and the same model weights, in alternating rounds;
medians of the per-step process CPU time (the first 5 steps of a round are warm-up).
"""

from __future__ import annotations

import argparse
import statistics
import time

import torch
from lerobot.configs.types import FeatureType, PolicyFeature
from lerobot.optim.optimizers import AdamWConfig, OptimizerConfig
from lerobot.policies.act.configuration_act import ACTConfig
from lerobot.policies.act.modeling_act import ACTPolicy

from rmb_lerobot.cli.quickstart import ACT_LR, ACT_WEIGHT_DECAY
from rmb_lerobot.optim.fused_adamw import FusedAdamWConfig

CAMERAS = ("front", "hand")
SIZE, BATCH, CHUNK, DOF = 64, 8, 20, 7


def quickstart_act() -> ACTPolicy:
    """LeRobot's ACT at the quick start's size (rmb_lerobot.cli.quickstart.ACT_CPU_ARGS)."""
    features = {"observation.state": PolicyFeature(FeatureType.STATE, (DOF,))}
    for camera in CAMERAS:
        features[f"observation.images.{camera}"] = PolicyFeature(
            FeatureType.VISUAL, (3, SIZE, SIZE)
        )
    config = ACTConfig(
        input_features=features,
        output_features={"action": PolicyFeature(FeatureType.ACTION, (DOF,))},
        pretrained_backbone_weights=None,
        chunk_size=CHUNK,
        n_action_steps=10,
        dim_model=256,
        dim_feedforward=1024,
        n_encoder_layers=2,
        device="cpu",
    )
    return ACTPolicy(config)


def random_batch(generator: torch.Generator) -> dict[str, torch.Tensor]:
    batch = {
        "observation.state": torch.randn(BATCH, DOF, generator=generator),
        "action": torch.randn(BATCH, CHUNK, DOF, generator=generator),
        "action_is_pad": torch.zeros(BATCH, CHUNK, dtype=torch.bool),
    }
    for camera in CAMERAS:
        batch[f"observation.images.{camera}"] = torch.rand(
            BATCH, 3, SIZE, SIZE, generator=generator
        )
    return batch


def cpu_seconds_per_step(config: OptimizerConfig, weights: dict, steps: int) -> tuple[float, float]:
    """Median CPU seconds of a whole training step and of the optimizer step alone."""
    policy = quickstart_act()
    policy.load_state_dict(weights)
    optimizer = config.build(policy.get_optim_params())
    generator = torch.Generator().manual_seed(0)
    whole, optimizer_only = [], []
    for step in range(steps + 5):
        batch = random_batch(generator)
        start = time.process_time()
        loss, _ = policy.forward(batch)
        loss.backward()
        before_step = time.process_time()
        optimizer.step()
        optimizer.zero_grad()
        end = time.process_time()
        if step >= 5:
            whole.append(end - start)
            optimizer_only.append(end - before_step)
    return statistics.median(whole), statistics.median(optimizer_only)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=30, help="measured steps per round")
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    torch.manual_seed(0)
    weights = quickstart_act().state_dict()
    options = {"lr": ACT_LR, "weight_decay": ACT_WEIGHT_DECAY}
    configs = {
        "adamw (LeRobot)": AdamWConfig(**options),
        "adamw_fused": FusedAdamWConfig(**options),
    }
    results: dict[str, list[tuple[float, float]]] = {name: [] for name in configs}
    for _ in range(args.rounds):
        for name, config in configs.items():
            results[name].append(cpu_seconds_per_step(config, weights, args.steps))
    print(
        f"quick start ACT, {torch.get_num_threads()} torch thread(s), batch {BATCH}, "
        f"{args.rounds} rounds x {args.steps} steps (medians)\n"
    )
    print("| optimizer | CPU s/step | optimizer CPU s/step | step ratio |")
    print("|---|---:|---:|---:|")
    base = statistics.median(w for w, _ in results["adamw (LeRobot)"])
    for name, runs in results.items():
        whole = statistics.median(w for w, _ in runs)
        step = statistics.median(o for _, o in runs)
        print(f"| {name} | {whole:.3f} | {step:.3f} | {whole / base:.2f} |")


if __name__ == "__main__":
    main()
