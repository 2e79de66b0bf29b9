"""A LeRobot policy checkpoint and a LeRobot env type, as the rollout server uses them.

Everything goes through LeRobot's own factories, as ``lerobot-eval`` does: the policy and its
saved pre/post processors from the checkpoint directory, the env from the env config registry
(``--env.type=rmb_ur5e_pick`` ...), the env's pre/post processors from its config. Each step
feeds the observation through ``preprocess_observation``, puts the instruction in the batch's
``task`` entry, runs the env and policy preprocessors, ``select_action`` and the
postprocessors: the same path an evaluation takes, with the instruction in place of the env's
own ``task_description``.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import gymnasium as gym
import numpy as np

if TYPE_CHECKING:
    from lerobot.envs.configs import EnvConfig


def _batched(tree: Any) -> Any:
    """One observation as a vector env of one delivers it: a leading axis of 1 on every array."""
    if isinstance(tree, Mapping):
        return {k: _batched(v) for k, v in tree.items()}
    return np.asarray(tree)[None]


class LeRobotRolloutPolicy:
    """:class:`~rmb_lerobot.rollout.server.RolloutPolicy` over a LeRobot ``PreTrainedPolicy``
    and its processors; build it with :meth:`from_pretrained`."""

    def __init__(
        self, policy, preprocessor, postprocessor, env_preprocessor=None, env_postprocessor=None
    ):
        self.policy = policy
        self.preprocessor = preprocessor
        self.postprocessor = postprocessor
        self.env_preprocessor = env_preprocessor
        self.env_postprocessor = env_postprocessor

    @classmethod
    def from_pretrained(
        cls, path: str | Path, env_cfg: EnvConfig, device: str | None = None
    ) -> LeRobotRolloutPolicy:
        """Load the checkpoint at ``path`` (a ``pretrained_model`` directory) with LeRobot's
        factory; ``device`` overrides the checkpoint's (e.g. ``cpu``)."""
        from lerobot.configs.policies import PreTrainedConfig
        from lerobot.envs.factory import make_env_pre_post_processors
        from lerobot.policies.factory import make_policy, make_pre_post_processors

        path = Path(path)
        if not (path / "config.json").is_file():
            raise FileNotFoundError(
                f"{path}: not a policy checkpoint (no config.json); give the pretrained_model "
                "directory, e.g. outputs/train/checkpoints/last/pretrained_model"
            )
        config = PreTrainedConfig.from_pretrained(path)
        config.pretrained_path = path
        if device is not None:
            config.device = device
        policy = make_policy(cfg=config, env_cfg=env_cfg)
        policy.eval()
        preprocessor, postprocessor = make_pre_post_processors(
            policy_cfg=config,
            pretrained_path=str(path),
            preprocessor_overrides={"device_processor": {"device": str(config.device)}},
        )
        env_pre, env_post = make_env_pre_post_processors(env_cfg=env_cfg, policy_cfg=config)
        return cls(policy, preprocessor, postprocessor, env_pre, env_post)

    def reset(self) -> None:
        self.policy.reset()
        for pipeline in (
            self.preprocessor,
            self.postprocessor,
            self.env_preprocessor,
            self.env_postprocessor,
        ):
            if pipeline is not None and hasattr(pipeline, "reset"):
                pipeline.reset()

    def act(self, observation: Mapping[str, Any], instruction: str) -> np.ndarray:
        import torch
        from lerobot.envs.utils import preprocess_observation
        from lerobot.utils.constants import ACTION

        batch = preprocess_observation(_batched(observation))
        batch["task"] = [instruction]
        if self.env_preprocessor is not None:
            batch = self.env_preprocessor(batch)
        batch = self.preprocessor(batch)
        with torch.inference_mode():
            action = self.policy.select_action(batch)
        action = self.postprocessor(action)
        if self.env_postprocessor is not None:
            action = self.env_postprocessor({ACTION: action})[ACTION]
        return action.to("cpu").numpy()[0]


def make_rollout_env(env_cfg: EnvConfig) -> tuple[gym.Env, Any]:
    """One env of ``env_cfg`` built by LeRobot's ``make_env`` (a vector env of one, as
    ``lerobot-eval --eval.batch_size=1``); returns ``(env, vector_env)``: step the env, close
    the vector env."""
    from lerobot.envs.factory import make_env

    envs = make_env(env_cfg, n_envs=1, use_async_envs=False)
    vector = next(iter(next(iter(envs.values())).values()))
    if not isinstance(vector, gym.vector.SyncVectorEnv):
        vector.close()
        raise TypeError(f"env type {env_cfg.type!r} did not build a SyncVectorEnv ({type(vector)})")
    return vector.envs[0], vector
