"""LeRobot's pi0 and pi05 on a converted RMB dataset, offline, up to the weights.

Two things are downloaded online and stand in here: the gated PaliGemma tokenizer (a WordLevel
tokenizer built from the task strings, handed to LeRobot's own ``TokenizerProcessorStep``) and
the 3B-parameter networks (shrunk by ``tiny_vla.tiny_pi_networks``: the sizes are not config
fields). Everything else - features from the dataset, rename map, processors, flow-matching
loss, action queue, ``lerobot-train`` - is LeRobot's code on our data.
"""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest
import torch

from rmb_lerobot import lerobot_names as N
from rmb_lerobot.errors import RmbFormatError
from rmb_lerobot.policies_extra import vla

HERE = Path(__file__).parent
spec = importlib.util.spec_from_file_location("tiny_vla", HERE / "tiny_vla.py")
tiny_vla = importlib.util.module_from_spec(spec)
spec.loader.exec_module(tiny_vla)

CHUNK = 4
TINY = {"chunk_size": CHUNK, "n_action_steps": CHUNK, "image_resolution": (32, 32)}
TINY |= {"num_inference_steps": 2, "tokenizer_max_length": 16, "device": "cpu"}


@pytest.fixture(scope="module")
def converted(shared_expert_dataset) -> Path:
    """One scripted Insert demo (front + hand cameras, 32x32) as ``rmb-convert`` writes it;
    built once per run for the VLA tests (pi0, SmolVLA, GR00T), read-only."""
    return shared_expert_dataset("insert", cameras=("front", "hand"), size=32)


@pytest.fixture
def local_tokenizers(monkeypatch, tmp_path):
    """The Hub's tokenizers replaced by one built here: records the names LeRobot asks for."""
    from lerobot.processor import tokenizer_processor
    from transformers import AutoTokenizer

    directory = tiny_vla.build_tokenizer(
        tmp_path / "tokenizer", ["Insert the peg into the hole.", "Put the banana in the basket."]
    )
    asked: list[str] = []

    class LocalAutoTokenizer:
        @staticmethod
        def from_pretrained(name, *args, **kwargs):
            asked.append(name)
            return AutoTokenizer.from_pretrained(directory)

    monkeypatch.setattr(tokenizer_processor, "AutoTokenizer", LocalAutoTokenizer)
    return type("LocalTokenizers", (), {"asked": asked, "directory": directory})


def dataset_batch(root: Path, size: int, chunk: int) -> dict:
    from lerobot.datasets import LeRobotDataset

    dataset = LeRobotDataset(
        f"local/{root.name}",
        root=root,
        delta_timestamps={"action": [i / 31.25 for i in range(chunk)]},
    )
    loader = torch.utils.data.DataLoader(dataset, batch_size=size, shuffle=False)
    return next(iter(loader))


def test_recipes_map_our_cameras_to_the_checkpoints_slots(converted):
    features = vla.read_features(converted)
    assert vla.rgb_cameras(features) == ["front", "hand"]
    assert vla.camera_rename_map(["front", "hand"], "pi0") == {
        N.image_key("front"): N.image_key("base_0_rgb"),
        N.image_key("hand"): N.image_key("left_wrist_0_rgb"),
    }
    dual = ["front", "left", "right", "rear", "left_hand", "right_hand"]
    assert list(vla.camera_rename_map(dual, "pi05").items()) == [
        (N.image_key("front"), N.image_key("base_0_rgb")),
        (N.image_key("left_hand"), N.image_key("left_wrist_0_rgb")),
        (N.image_key("right_hand"), N.image_key("right_wrist_0_rgb")),
    ]
    assert list(vla.camera_rename_map(["hand", "front"], "smolvla").values()) == [
        N.image_key("camera1"),
        N.image_key("camera2"),
    ]
    assert vla.camera_rename_map(dual, "groot") == {}
    args = vla.train_args(converted, "pi0")
    assert "--policy.path=lerobot/pi0_base" in args and f"--dataset.root={converted}" in args
    rename = json.loads(next(a for a in args if a.startswith("--rename_map=")).split("=", 1)[1])
    assert rename == vla.camera_rename_map(["front", "hand"], "pi0")
    with pytest.raises(ValueError, match="unknown VLA"):
        vla.train_args(converted, "pi1")


def test_depth_cameras_are_refused_naming_them(tmp_path, converted):
    info = json.loads((converted / "meta" / "info.json").read_text())
    info["features"][N.depth_image_key("front")] = {
        "dtype": "video",
        "shape": [32, 32, 1],
        "names": ["height", "width", "channels"],
        "info": {"video.is_depth_map": True},
    }
    (tmp_path / "meta").mkdir()
    (tmp_path / "meta" / "info.json").write_text(json.dumps(info))
    assert vla.rgb_cameras(info["features"]) == ["front", "hand"]
    with pytest.raises(RmbFormatError, match=r"depth cameras \['front_depth'\].*without --depth"):
        vla.train_args(tmp_path, "pi0")


@pytest.mark.parametrize("policy_type", ["pi0", "pi05"])
def test_a_training_step_and_actions_through_lerobots_factories(
    policy_type, converted, local_tokenizers, no_network
):
    from lerobot.configs.policies import PreTrainedConfig
    from lerobot.datasets import LeRobotDatasetMetadata
    from lerobot.policies.factory import make_policy, make_pre_post_processors

    meta = LeRobotDatasetMetadata(f"local/{converted.name}", root=converted)
    config = PreTrainedConfig.get_choice_class(policy_type)(**TINY)
    with tiny_vla.tiny_pi_networks():
        policy = make_policy(config, ds_meta=meta)
    pre, post = make_pre_post_processors(config, dataset_stats=meta.stats)
    # The processor asks for PaliGemma's (gated) tokenizer: the download boundary.
    assert local_tokenizers.asked == [vla.PALIGEMMA_TOKENIZER]
    assert set(config.image_features) == {N.image_key("front"), N.image_key("hand")}

    batch = dataset_batch(converted, 2, CHUNK)
    assert batch["task"][0].startswith("Insert")  # the episode's RMB task_desc
    processed = pre(batch)
    tokens = processed["observation.language.tokens"]
    assert tokens.shape == (2, 16) and (tokens != 0).any()  # the task text became tokens
    policy.train()
    loss, info = policy.forward(processed)
    assert torch.isfinite(loss) and len(info["loss_per_dim"]) == 7
    loss.backward()
    optimizer = torch.optim.AdamW(policy.parameters(), lr=1e-3)
    optimizer.step()

    policy.reset()
    observation = {k: v[:1] for k, v in batch.items() if not k.startswith("action")}
    observation["task"] = batch["task"][:1]
    action = post(policy.select_action(pre(observation)))
    assert action.shape == (1, 7) and torch.isfinite(action).all()
    assert len(policy._action_queue) == CHUNK - 1  # the rest of the chunk is queued


@pytest.mark.timeout(1200)  # lerobot-train in a subprocess (tests/conftest.py)
def test_lerobot_train_fine_tunes_a_local_checkpoint_with_the_recipes_rename_map(
    converted, local_tokenizers, tmp_path
):
    """The online recipe (``vla.train_args(..., "pi0")``: ``--policy.path=lerobot/pi0_base``
    and the rename map) with a tiny local checkpoint in pi0_base's place: same camera slots,
    its processor pointing at the local tokenizer."""
    from lerobot.configs.types import FeatureType, PolicyFeature
    from lerobot.policies.factory import make_pre_post_processors
    from lerobot.policies.pi0 import PI0Config, PI0Policy
    from lerobot.processor import TokenizerProcessorStep

    slots = {key: PolicyFeature(FeatureType.VISUAL, (3, 32, 32)) for key in vla.PI_CAMERA_SLOTS}
    config = PI0Config(
        input_features=slots | {N.STATE: PolicyFeature(FeatureType.STATE, (32,))},
        output_features={N.ACTION_KEY: PolicyFeature(FeatureType.ACTION, (32,))},
        **TINY,
    )
    with tiny_vla.tiny_pi_networks():
        policy = PI0Policy(config)
    pre, post = make_pre_post_processors(config, dataset_stats={})
    (tokenizer_step,) = [s for s in pre.steps if isinstance(s, TokenizerProcessorStep)]
    tokenizer_step.tokenizer_name = str(local_tokenizers.directory)  # saved in PaliGemma's place
    checkpoint = tmp_path / "tiny_pi0_base"
    for part in (policy, pre, post):
        part.save_pretrained(checkpoint)

    args = vla.train_args(converted, "pi0", checkpoint=str(checkpoint))
    _, trained = tiny_vla.lerobot_train_two_steps(args, tmp_path, patched=True)
    saved = json.loads((trained / "config.json").read_text())
    assert saved["type"] == "pi0" and saved["chunk_size"] == CHUNK
    assert set(saved["input_features"]) >= set(vla.PI_CAMERA_SLOTS)
    steps = json.loads((trained / "policy_preprocessor.json").read_text())["steps"]
    config_of = {step["registry_name"]: step.get("config", {}) for step in steps}
    assert config_of["rename_observations_processor"]["rename_map"] == vla.camera_rename_map(
        ["front", "hand"], "pi0"
    )
    assert config_of["tokenizer_processor"]["tokenizer_name"] == str(local_tokenizers.directory)
