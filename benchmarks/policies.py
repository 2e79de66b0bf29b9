"""Policy cost on CPU: parameters, training step time and inference latency, per policy.

Usage::

    .venv/bin/python benchmarks/policies.py [--policies mlp sarnn dp3 flow_policy maniflow mt_act
        act diffusion]
        [--threads 1]

Every policy gets its default configuration (backbones randomly initialised: no weights are
downloaded) and the same inputs: a 7-D state and ``--cameras`` RGB cameras of ``--image-size``.
LeRobot's ACT and Diffusion are measured in the same run as references. A training step is
forward + backward + the policy's own optimizer preset on a random batch shaped by the
policy's delta indices (so SARNN's batch holds ``sequence_length`` steps per sample, ACT's a
100-action chunk). DP3 and Flow Policy also get the first camera's depth (a random surface
0.5-1.2 m away, in mm as LeRobot decodes it) and sample their point clouds anew every step (cache
off: the cost of a first epoch; later epochs reuse the clouds of frames already seen). "query"
is one call of ``select_action`` right after ``reset()`` (always a model evaluation); "per env
step" is the mean over a 100-step rollout, where chunking policies reuse queued actions and
SARNN holds its command for ``frame_skip`` steps.
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import time

import torch
from lerobot.configs.types import FeatureType, PolicyFeature
from lerobot.policies.factory import get_policy_class, make_policy_config

import lerobot_env_rmb  # noqa: F401 - registers our policies, as LeRobot's plugin discovery

STATE_DIM = ACTION_DIM = 7  # UR5e joints + gripper
POINT_CLOUD_ARGS = {"camera_fovy": 45.0, "point_cloud_cache_size": 0}
DEPTH_POLICIES = {"dp3": POINT_CLOUD_ARGS, "flow_policy": POINT_CLOUD_ARGS}
DEPTH_SUFFIX = "_depth"
TASK = "Put the banana in the blue basket."  # one of Pick's instructions


def build(policy_type: str, cameras: int, image_size: int):
    inputs = {"observation.state": PolicyFeature(FeatureType.STATE, (STATE_DIM,))}
    for i in range(cameras):
        inputs[f"observation.images.cam{i}"] = PolicyFeature(
            FeatureType.VISUAL, (3, image_size, image_size)
        )
    outputs = {"action": PolicyFeature(FeatureType.ACTION, (ACTION_DIM,))}
    config_cls = type(make_policy_config(policy_type, device="cpu"))
    kwargs = {"input_features": inputs, "output_features": outputs, "device": "cpu"}
    if policy_type in DEPTH_POLICIES:
        inputs[f"observation.images.cam0{DEPTH_SUFFIX}"] = PolicyFeature(
            FeatureType.VISUAL, (1, image_size, image_size)
        )
        kwargs |= DEPTH_POLICIES[policy_type]
    if "pretrained_backbone_weights" in {f.name for f in dataclasses.fields(config_cls)}:
        kwargs["pretrained_backbone_weights"] = None
    config = make_policy_config(policy_type, **kwargs)
    return get_policy_class(policy_type)(config)


def random_input(key: str, shape: tuple[int, ...]) -> torch.Tensor:
    """Images in [0, 1]; depth in millimetres, 0.5-1.2 m (inside DP3's default crop)."""
    if key.endswith(DEPTH_SUFFIX):
        return 500.0 + 700.0 * torch.rand(shape)
    return torch.rand(shape)


def _task(config, batch_size: int) -> dict[str, list[str]]:
    """The task strings language-conditioned policies (mt_act) read; nothing for others."""
    return {"task": [TASK] * batch_size} if hasattr(config, "text_encoder") else {}


def training_batch(config, batch_size: int) -> dict[str, torch.Tensor]:
    obs_steps = config.observation_delta_indices
    batch = {}
    for key, feature in config.input_features.items():
        shape = (batch_size, *(() if obs_steps is None else (len(obs_steps),)), *feature.shape)
        batch[key] = random_input(key, shape)
    n_actions = len(config.action_delta_indices)
    batch["action"] = torch.randn(batch_size, n_actions, ACTION_DIM)
    batch["action_is_pad"] = torch.zeros(batch_size, n_actions, dtype=torch.bool)
    return batch | _task(config, batch_size)


def observation(config) -> dict[str, torch.Tensor]:
    obs = {key: random_input(key, (1, *ft.shape)) for key, ft in config.input_features.items()}
    return obs | _task(config, 1)


def train_step_seconds(policy, batch_size: int, steps: int) -> float:
    optimizer = policy.config.get_optimizer_preset().build(policy.get_optim_params())
    batch = training_batch(policy.config, batch_size)
    policy.train()
    times = []
    for _ in range(steps + 1):  # the first step (allocation, lazy init) is not timed
        start = time.perf_counter()
        loss, _ = policy.forward(batch)
        optimizer.zero_grad()
        loss.backward()
        optimizer.step()
        times.append(time.perf_counter() - start)
    return statistics.median(times[1:])


def inference_ms(policy, queries: int, rollout: int) -> tuple[float, float]:
    obs = observation(policy.config)
    policy.eval()
    query = []
    for _ in range(queries + 1):
        policy.reset()
        start = time.perf_counter()
        policy.select_action(dict(obs))
        query.append(time.perf_counter() - start)
    policy.reset()
    start = time.perf_counter()
    for _ in range(rollout):
        policy.select_action(dict(obs))
    per_step = (time.perf_counter() - start) / rollout
    return 1e3 * statistics.median(query[1:]), 1e3 * per_step


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--policies",
        nargs="+",
        default=["mlp", "sarnn", "dp3", "flow_policy", "maniflow", "mt_act", "act", "diffusion"],
    )
    parser.add_argument("--cameras", type=int, default=2, help="RMB's UR5e default: front, hand")
    parser.add_argument("--image-size", type=int, default=128, help="our env's default, square")
    parser.add_argument("--batch-size", type=int, default=8)
    parser.add_argument("--train-steps", type=int, default=3, help="timed steps (median)")
    parser.add_argument("--queries", type=int, default=5, help="timed queries (median)")
    parser.add_argument("--rollout", type=int, default=100, help="env steps for the mean")
    parser.add_argument("--threads", type=int, default=None, help="torch intra-op threads")
    args = parser.parse_args()
    if args.threads:
        torch.set_num_threads(args.threads)

    print(
        f"torch {torch.__version__}, {torch.get_num_threads()} threads; {args.cameras} x "
        f"{args.image_size}x{args.image_size} cameras, batch {args.batch_size}\n"
    )
    print("| policy | parameters | window per sample | train step s | query ms | per env step ms |")
    print("|---|---:|---|---:|---:|---:|")
    for policy_type in args.policies:
        torch.manual_seed(0)
        policy = build(policy_type, args.cameras, args.image_size)
        params = sum(p.numel() for p in policy.parameters())
        config = policy.config
        window = (
            f"{len(config.observation_delta_indices or [0])} obs, "
            f"{len(config.action_delta_indices)} actions"
        )
        step = train_step_seconds(policy, args.batch_size, args.train_steps)
        query, per_step = inference_ms(policy, args.queries, args.rollout)
        print(
            f"| {policy_type} | {params / 1e6:.2f} M | {window} | {step:.2f} | {query:.1f} | "
            f"{per_step:.2f} |",
            flush=True,
        )


if __name__ == "__main__":
    main()
