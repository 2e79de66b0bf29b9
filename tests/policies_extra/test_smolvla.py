"""LeRobot's SmolVLA on a converted RMB dataset, offline, up to the weights.

SmolVLA downloads two Hub repositories: the checkpoint ``lerobot/smolvla_base`` (config,
weights, processors) and its VLM backbone ``HuggingFaceTB/SmolVLM2-500M-Video-Instruct``, named by
the config field ``vlm_model_name``: the policy loads that repo's config (and, with
``load_vlm_weights`` as smolvla_base sets it, its weights) and its processor, whose tokenizer
gives the image-token ids, and the preprocessor's tokenizer step loads the same repo's
tokenizer. Here the backbone is a tiny SmolVLM2 built locally (``tiny_vla.build_smolvlm``):
passed by path in ``vlm_model_name``, and served under the Hub ids from a seeded offline cache
to the unmodified ``lerobot-train`` with the recipe's own arguments. Everything else - features
from the dataset, rename map, task tokens, flow-matching loss, action queue - is LeRobot's code
on our data.
"""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest
import torch

from rmb_lerobot import lerobot_names as N
from rmb_lerobot.policies_extra import vla

HERE = Path(__file__).parent
spec = importlib.util.spec_from_file_location("tiny_vla", HERE / "tiny_vla.py")
tiny_vla = importlib.util.module_from_spec(spec)
spec.loader.exec_module(tiny_vla)

CHUNK = 4
CHECKPOINT, BACKBONE = vla.RECIPES["smolvla"].downloads
TEXTS = ["Insert the square peg into the hole.", "Put the banana in the blue basket."]


@pytest.fixture(scope="module")
def converted(shared_expert_dataset) -> Path:
    """One scripted Insert demo (front + hand cameras, 32x32) as ``rmb-convert`` writes it;
    built once per run for the VLA tests (pi0, SmolVLA, GR00T), read-only."""
    return shared_expert_dataset("insert", cameras=("front", "hand"), size=32)


@pytest.fixture(scope="module")
def smolvlm(tmp_path_factory) -> Path:
    """The tiny SmolVLM2 (config, weights, processor, tokenizer) in a local directory."""
    return tiny_vla.build_smolvlm(tmp_path_factory.mktemp("smolvlm") / "smolvlm2", TEXTS)


def test_the_recipe_is_smolvla_bases_and_maps_scene_then_wrist_cameras(converted):
    recipe = vla.RECIPES["smolvla"]
    assert (recipe.policy_type, recipe.checkpoint) == ("smolvla", "lerobot/smolvla_base")
    assert recipe.camera_slots == tuple(N.image_key(f"camera{i}") for i in (1, 2, 3))
    assert (recipe.chunk_size, recipe.n_action_steps) == (50, 50)  # SmolVLAConfig's defaults
    from lerobot.policies.smolvla import SmolVLAConfig

    defaults = SmolVLAConfig()
    assert (defaults.chunk_size, defaults.n_action_steps) == (recipe.chunk_size, 50)
    assert defaults.vlm_model_name == BACKBONE

    assert vla.camera_rename_map(["hand", "front"], "smolvla") == {
        N.image_key("front"): N.image_key("camera1"),
        N.image_key("hand"): N.image_key("camera2"),
    }
    # Every scene camera recorded: the wrist view still gets a slot (the second, as for pi0).
    every = ["front", "left", "right", "hand"]
    assert list(vla.camera_rename_map(every, "smolvla").items()) == [
        (N.image_key("front"), N.image_key("camera1")),
        (N.image_key("hand"), N.image_key("camera2")),
        (N.image_key("left"), N.image_key("camera3")),
    ]
    dual = ["front", "left", "right", "rear", "left_hand", "right_hand"]
    assert set(vla.camera_rename_map(dual, "smolvla")) == set(vla.camera_rename_map(dual, "pi0"))

    args = vla.train_args(converted, "smolvla")
    assert args[:3] == [
        f"--dataset.repo_id=local/{converted.name}",
        f"--dataset.root={converted}",
        "--policy.path=lerobot/smolvla_base",
    ]
    rename = json.loads(args[3].removeprefix("--rename_map="))
    assert rename == {N.image_key("front"): recipe.camera_slots[0]} | {
        N.image_key("hand"): recipe.camera_slots[1]
    }
    assert not any(a.startswith("--policy.chunk_size") for a in args)  # the checkpoint's 50


def test_a_training_step_and_actions_through_lerobots_factories(converted, smolvlm, no_network):
    from lerobot.configs.policies import PreTrainedConfig
    from lerobot.datasets import LeRobotDataset, LeRobotDatasetMetadata
    from lerobot.policies.factory import make_policy, make_pre_post_processors
    from lerobot.processor import TokenizerProcessorStep
    from transformers import AutoTokenizer

    meta = LeRobotDatasetMetadata(f"local/{converted.name}", root=converted)
    config = PreTrainedConfig.get_choice_class("smolvla")(
        vlm_model_name=str(smolvlm),  # the download boundary: a local SmolVLM2 directory
        chunk_size=CHUNK,
        n_action_steps=CHUNK,
        num_steps=2,
        device="cpu",
    )
    policy = make_policy(config, ds_meta=meta)
    pre, post = make_pre_post_processors(config, dataset_stats=meta.stats)
    (tokenizer_step,) = [s for s in pre.steps if isinstance(s, TokenizerProcessorStep)]
    assert tokenizer_step.tokenizer_name == str(smolvlm)  # the backbone's own tokenizer
    assert set(config.image_features) == {N.image_key("front"), N.image_key("hand")}
    # Fine-tuning trains the action expert; the VLM (here random) stays frozen.
    vlm = policy.model.vlm_with_expert.vlm
    assert not any(p.requires_grad for p in vlm.parameters())
    expert = policy.model.action_out_proj.weight
    assert expert.requires_grad

    dataset = LeRobotDataset(
        f"local/{converted.name}",
        root=converted,
        delta_timestamps={"action": [i / meta.fps for i in range(CHUNK)]},
    )
    batch = next(iter(torch.utils.data.DataLoader(dataset, batch_size=2)))
    assert batch["task"] == [TEXTS[0]] * 2  # the episode's RMB task_desc
    processed = pre(batch)
    tokens = processed["observation.language.tokens"]
    expected = AutoTokenizer.from_pretrained(smolvlm)(TEXTS[0] + "\n")["input_ids"]
    assert tokens.tolist() == [expected] * 2  # the task text, tokenized by SmolVLM's tokenizer
    assert "<unk>" not in AutoTokenizer.from_pretrained(smolvlm).decode(expected)

    policy.train()
    loss, _ = policy.forward(processed)
    assert torch.isfinite(loss) and loss.item() > 0
    loss.backward()
    assert expert.grad is not None and expert.grad.abs().sum() > 0
    before = expert.detach().clone()
    torch.optim.AdamW([p for p in policy.parameters() if p.requires_grad], lr=1e-3).step()
    assert not torch.equal(before, expert)

    policy.reset()
    observation = {k: v[:1] for k, v in batch.items() if not k.startswith("action")}
    observation["task"] = batch["task"][:1]
    action = post(policy.select_action(pre(observation)))
    assert action.shape == (1, 7) and torch.isfinite(action).all()
    assert len(policy._queues["action"]) == CHUNK - 1  # the rest of the chunk is queued


@pytest.mark.timeout(1200)  # lerobot-train in a subprocess (tests/conftest.py)
def test_lerobot_train_runs_the_recipe_with_the_hub_replaced_by_a_local_cache(
    converted, smolvlm, tmp_path
):
    """The unmodified ``lerobot-train`` with ``vla.train_args(..., "smolvla")`` (``--policy.path=
    lerobot/smolvla_base``, the rename map), offline, its Hugging Face cache holding a tiny
    smolvla_base and the tiny SmolVLM2 under the real Hub ids."""
    from safetensors.torch import load_file

    base = tiny_vla.build_smolvla_base(tmp_path / "smolvla_base", smolvlm, BACKBONE)
    cache = tmp_path / "hub"
    tiny_vla.seed_hub_cache(cache, CHECKPOINT, base)
    tiny_vla.seed_hub_cache(cache, BACKBONE, smolvlm)
    stdout, trained = tiny_vla.lerobot_train_two_steps(
        vla.train_args(converted, "smolvla"), tmp_path, hub_cache=cache
    )
    assert f"Loading  {BACKBONE} weights" in stdout  # load_vlm_weights, from the cache
    saved = json.loads((trained / "config.json").read_text())
    assert (saved["type"], saved["vlm_model_name"], saved["chunk_size"]) == (
        "smolvla",
        BACKBONE,
        50,
    )
    assert set(saved["input_features"]) >= set(vla.SMOLVLA_CAMERA_SLOTS)
    assert saved["output_features"]["action"]["shape"] == [7]  # our UR5e's 7-d action
    steps = json.loads((trained / "policy_preprocessor.json").read_text())["steps"]
    config_of = {step["registry_name"]: step.get("config", {}) for step in steps}
    assert config_of["rename_observations_processor"]["rename_map"] == vla.camera_rename_map(
        ["front", "hand"], "smolvla"
    )
    assert config_of["tokenizer_processor"]["tokenizer_name"] == BACKBONE
    # Two optimizer steps moved the action expert and left the frozen VLM as smolvla_base had it.
    start, end = load_file(base / "model.safetensors"), load_file(trained / "model.safetensors")
    key = "model.action_out_proj.weight"
    assert not torch.equal(start[key], end[key])
    vlm = [k for k in start if ".vlm." in k]
    assert vlm and all(torch.equal(start[k], end[k]) for k in vlm)
