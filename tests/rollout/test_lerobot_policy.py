"""The rollout on our LeRobot env types and with a LeRobot policy: Pick takes the instruction
in ``reset``, and the instruction reaches a language-conditioned policy as its ``task``."""

from __future__ import annotations

import threading

import numpy as np
import pytest
import torch
from lerobot.configs.types import FeatureType, PolicyFeature
from lerobot.envs.configs import EnvConfig
from lerobot.envs.factory import make_env_pre_post_processors
from lerobot.policies.factory import make_pre_post_processors

import lerobot_env_rmb  # noqa: F401 - registers the env and policy types, as LeRobot's discovery
from rmb_lerobot.envs.tasks.pick import INSTRUCTIONS
from rmb_lerobot.policies_extra.mt_act import MTACTConfig, MTACTPolicy
from rmb_lerobot.rollout import RolloutClient, RolloutError, RolloutServer, takes_instruction
from rmb_lerobot.rollout.lerobot_policy import LeRobotRolloutPolicy, make_rollout_env

SIZE = 32


def pick_config(**overrides) -> EnvConfig:
    kwargs = {"cameras": ["front"], "image_width": SIZE, "image_height": SIZE} | overrides
    return EnvConfig.get_choice_class("rmb_ur5e_pick")(**kwargs)


class HoldPolicy:
    """Commands the measured joints (the arm holds still); records each call's task."""

    def __init__(self):
        self.tasks: list[str] = []

    def reset(self) -> None:
        pass

    def act(self, observation, instruction: str) -> np.ndarray:
        self.tasks.append(instruction)
        return np.asarray(observation["agent_pos"], dtype=np.float32)


def test_pick_from_lerobots_env_registry_takes_the_instruction():
    env, vector = make_rollout_env(pick_config(episode_length=3))
    policy = HoldPolicy()
    assert takes_instruction(env)
    wanted = INSTRUCTIONS[7]
    replies: dict = {}

    def client() -> None:
        with RolloutClient(server.address, timeout=60) as c:
            with pytest.raises(RolloutError, match="unknown instruction") as refused:
                c.instruct("Put the piano in the blue basket.")
            replies["refused"] = refused.value.code
            replies["started"] = c.instruct(wanted)
            replies["result"] = c.result()

    # serve() runs in the thread that made the env: its OpenGL context belongs to that thread.
    server = RolloutServer(env, policy, "tcp:127.0.0.1:0", episodes=1)
    try:
        with server:
            thread = threading.Thread(target=client)
            thread.start()
            server.serve()
            thread.join(timeout=60)
        assert env.unwrapped.task_description == wanted  # the env's episode was that one
    finally:
        vector.close()
    assert replies["refused"] == "bad_instruction"
    assert replies["started"]["instruction"] == wanted
    result = replies["result"]
    assert (result["status"], result["reason"], result["steps"]) == ("failure", "max_steps", 3)
    assert policy.tasks == [wanted] * 3


def tiny_mt_act() -> MTACTPolicy:
    torch.manual_seed(0)
    config = MTACTConfig(
        input_features={
            "observation.state": PolicyFeature(FeatureType.STATE, (7,)),
            "observation.images.front": PolicyFeature(FeatureType.VISUAL, (3, SIZE, SIZE)),
        },
        output_features={"action": PolicyFeature(FeatureType.ACTION, (7,))},
        dim_model=32,
        n_heads=2,
        dim_feedforward=64,
        n_encoder_layers=1,
        n_decoder_layers=1,
        n_vae_encoder_layers=1,
        latent_dim=8,
        chunk_size=4,
        n_action_steps=4,
        device="cpu",
    )
    policy = MTACTPolicy(config)
    policy.eval()
    return policy


def test_the_instruction_is_the_policys_task_through_lerobots_processors():
    policy = tiny_mt_act()
    stats = {
        "observation.state": {"mean": torch.zeros(7), "std": torch.ones(7)},
        "observation.images.front": {
            "mean": torch.full((3, 1, 1), 0.5),
            "std": torch.full((3, 1, 1), 0.2),
        },
        "action": {"mean": torch.zeros(7), "std": torch.ones(7)},
    }
    pre, post = make_pre_post_processors(policy.config, dataset_stats=stats)
    env_cfg = pick_config()
    runner = LeRobotRolloutPolicy(
        policy, pre, post, *make_env_pre_post_processors(env_cfg, policy.config)
    )
    rng = np.random.default_rng(0)
    observation = {  # one unbatched observation, as the env returns it
        "pixels": {"front": rng.integers(0, 256, (SIZE, SIZE, 3), dtype=np.uint8)},
        "agent_pos": rng.normal(size=7).astype(np.float32),
    }

    def first_action(instruction: str) -> np.ndarray:
        runner.reset()
        return runner.act(observation, instruction)

    banana = first_action(INSTRUCTIONS[0])
    assert banana.shape == (7,) and banana.dtype == np.float32 and np.isfinite(banana).all()
    assert set(policy.text_encoder.cache) == {INSTRUCTIONS[0]}  # it was embedded as the task
    mug = first_action(INSTRUCTIONS[14])
    assert not np.allclose(mug, banana, atol=1e-6)  # same observation, other instruction
    np.testing.assert_allclose(first_action(INSTRUCTIONS[0]), banana, rtol=1e-5, atol=1e-6)
