"""LeRobot env types: registered on plugin import, features matching the dataset keys."""

import json
import subprocess
import sys

import numpy as np
import pytest
from lerobot.envs.configs import EnvConfig

import lerobot_env_rmb  # noqa: F401 - what LeRobot's plugin discovery imports
from rmb_lerobot.envs.lerobot_config import ENV_CONFIGS, action_dim
from rmb_lerobot.envs.registry import ENVS
from rmb_lerobot.registration import registered_env_types


def test_every_table_entry_is_a_lerobot_env_type():
    assert registered_env_types() == sorted(e.lerobot_type for e in ENVS.values())
    for entry in ENVS.values():
        config = EnvConfig.get_choice_class(entry.lerobot_type)()
        assert config.type == entry.lerobot_type and config.task == entry.rmb_env_name


def test_features_map_targets_are_the_dataset_keys():
    config = ENV_CONFIGS["rmb_ur5e_insert"](
        cameras=["front", "left"], image_width=96, image_height=64
    )
    assert config.features_map == {
        "action": "action",
        "agent_pos": "observation.state",
        "pixels/front": "observation.images.front",
        "pixels/left": "observation.images.left",
    }
    assert config.features["pixels/left"].shape == (64, 96, 3)
    assert config.features["agent_pos"].shape == (7,)
    assert config.features["action"].shape == (7,)


@pytest.mark.parametrize(("mode", "dim"), [("joint", 7), ("eef_abs", 10), ("eef_rel", 7)])
def test_action_dimension_follows_the_action_mode(mode, dim):
    assert action_dim(mode) == dim
    assert ENV_CONFIGS["rmb_ur5e_door"](action_mode=mode).features["action"].shape == (dim,)


def test_sync_vector_env_matches_the_features():
    config = ENV_CONFIGS["rmb_ur5e_insert"](cameras=["front"], image_width=32, image_height=24)
    envs = config.create_envs(n_envs=2)
    vec = envs["rmb_ur5e_insert"][0]
    try:
        obs, _ = vec.reset(seed=0)
        assert obs["pixels"]["front"].shape == (2, 24, 32, 3)
        assert obs["agent_pos"].shape == (2, 7) and obs["agent_pos"].dtype == np.float32
        _, _, _, _, info = vec.step(np.tile(obs["agent_pos"][:1], (2, 1)))
        assert "is_success" in info
        assert next(iter(vec.call("task_description"))).startswith("Insert")
    finally:
        vec.close()


def test_world_idx_evaluates_every_episode_in_that_world():
    config = ENV_CONFIGS["rmb_ur5e_insert"](cameras=[], world_idx=4)
    vec = config.create_envs(n_envs=2)["rmb_ur5e_insert"][0]
    try:
        for seed in (0, 7):
            _, info = vec.reset(seed=seed)
            assert list(info["world_idx"]) == [4, 4]
        _, info = vec.reset(seed=0, options={"world_idx": 2})  # an explicit option still wins
        assert list(info["world_idx"]) == [2, 2]
    finally:
        vec.close()


def test_instruction_evaluates_every_episode_with_that_instruction():
    """``lerobot-eval --env.type=rmb_ur5e_pick --env.instruction=...`` scores one instruction;
    the policy gets it as the task (the env's task_description)."""
    from rmb_lerobot.envs.tasks.pick import INSTRUCTIONS

    wanted = INSTRUCTIONS[5]
    config = ENV_CONFIGS["rmb_ur5e_pick"](cameras=[], instruction=wanted)
    vec = config.create_envs(n_envs=2)["rmb_ur5e_pick"][0]
    try:
        for seed in (0, 7, 11):  # without it, each seed draws its own
            vec.reset(seed=seed)
            assert list(vec.call("task_description")) == [wanted, wanted]
    finally:
        vec.close()


def test_instruction_is_refused_by_a_task_without_instructions():
    config = ENV_CONFIGS["rmb_ur5e_insert"](cameras=[], instruction="Insert it.")
    with pytest.raises(ValueError, match=r"'MujocoUR5eInsert' takes no instruction"):
        config.create_envs(n_envs=1)


def test_async_vector_env_uses_forkserver_workers():
    config = ENV_CONFIGS["rmb_ur5e_door"](cameras=[], episode_length=5)
    vec = config.create_envs(n_envs=2, use_async_envs=True)["rmb_ur5e_door"][0]
    try:
        obs, _ = vec.reset(seed=0)
        assert obs["agent_pos"].shape == (2, 7)
        assert vec.call("_max_episode_steps") == (5, 5)
    finally:
        vec.close()


TINY_ACT = """
import sys, torch
from lerobot.configs.types import FeatureType, PolicyFeature
from lerobot.policies.act.configuration_act import ACTConfig
from lerobot.policies.act.modeling_act import ACTPolicy
from lerobot.policies.factory import make_pre_post_processors

features = {"observation.state": PolicyFeature(FeatureType.STATE, (7,)),
            "observation.images.front": PolicyFeature(FeatureType.VISUAL, (3, 32, 32))}
config = ACTConfig(input_features=features,
                   output_features={"action": PolicyFeature(FeatureType.ACTION, (7,))},
                   pretrained_backbone_weights=None, dim_model=32, dim_feedforward=64, n_heads=2,
                   n_encoder_layers=1, n_decoder_layers=1, chunk_size=4, n_action_steps=4,
                   use_vae=False, device="cpu")
ones = lambda n: {"mean": torch.zeros(n), "std": torch.ones(n)}
stats = {"observation.state": ones(7), "action": ones(7),
         "observation.images.front": {"mean": torch.full((3, 1, 1), 0.5),
                                      "std": torch.full((3, 1, 1), 0.25)}}
pre, post = make_pre_post_processors(config, dataset_stats=stats)
for part in (ACTPolicy(config), pre, post):
    part.save_pretrained(sys.argv[1])
"""


@pytest.mark.timeout(1200)  # lerobot-eval in a subprocess (tests/conftest.py)
def test_lerobot_eval_cli_runs_on_an_rmb_env_type(tmp_path):
    # A tiny randomly initialised ACT is enough: the point is that the unmodified CLI builds
    # our env from --env.type and reports a success rate.
    checkpoint = tmp_path / "tiny_act"
    subprocess.run([sys.executable, "-c", TINY_ACT, str(checkpoint)], check=True, timeout=300)
    lerobot_eval = [sys.executable, "-m", "lerobot.scripts.lerobot_eval"]
    result = subprocess.run(
        [
            *lerobot_eval,
            f"--policy.path={checkpoint}",
            "--policy.device=cpu",
            "--env.type=rmb_ur5e_insert",
            "--env.cameras=[front]",
            "--env.image_width=32",
            "--env.image_height=32",
            "--env.episode_length=6",
            "--eval.n_episodes=1",
            "--eval.batch_size=1",
            f"--output_dir={tmp_path / 'eval'}",
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert result.returncode == 0, result.stderr[-3000:]
    info = json.loads((tmp_path / "eval" / "eval_info.json").read_text())
    assert info["overall"]["n_episodes"] == 1
    # 6 steps of an untrained ACT from the start pose cannot insert the peg: a success here
    # would be the env's ``is_success``, which lerobot-eval counts, firing with the peg out.
    assert info["overall"]["pc_success"] == 0.0
