"""LeRobot's GR00T N1.7 (``--policy.type=groot``) on a converted RMB dataset, offline, up to the
checkpoint download.

GR00T N1.7 fetches two things from the Hub: the 3B checkpoint (``snapshot_download`` of
``nvidia/GR00T-N1.7-3B`` when the policy is built) and Cosmos-Reason2-2B's tokenizer and image
processor (when the preprocessor first encodes a batch; the backbone's architecture is a config
LeRobot hard-codes, its weights come with the checkpoint). Here both are tiny models built
locally and handed over at exactly those calls, as the Hub-push tests replace the upload; the
rest - features, embodiment, state/action padding and masks, the VLM prompt, flow-matching loss,
``lerobot-train`` - is LeRobot's code on our data. ``meta/modality.json`` is not read by
LeRobot: it is checked against Isaac-GR00T's published schema.
"""

from __future__ import annotations

import importlib.util
import itertools
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
CHECKPOINT, BACKBONE = vla.RECIPES["groot"].downloads
TEXTS = ["Insert the peg into the hole.", "Put the banana in the basket."]
# Isaac-GR00T's LeRobotModalityMetadata (gr00t/data/schema.py): the fields a group may have.
GROUP_FIELDS = {"start", "end", "original_key", "absolute", "rotation_type", "dtype", "range"}
ROTATION_TYPES = {"axis_angle", "quaternion", "rotation_6d", "matrix"} | {
    f"euler_angles_{order}" for order in ("rpy", "ryp", "pry", "pyr", "yrp", "ypr")
}


@pytest.fixture(scope="module")
def converted(shared_expert_dataset) -> Path:
    """One scripted Insert demo (front + hand cameras, 32x32) as ``rmb-convert`` writes it;
    built once per run for the VLA tests (pi0, SmolVLA, GR00T), read-only."""
    return shared_expert_dataset("insert", cameras=("front", "hand"), size=32)


@pytest.fixture(scope="module")
def tiny_groot(tmp_path_factory) -> dict[str, Path]:
    """A tiny GR00T N1.7 checkpoint and its tiny Qwen3-VL backbone files, built here."""
    root = tmp_path_factory.mktemp("tiny_groot")
    backbone = tiny_vla.build_qwen3_vl(root / "qwen3_vl", TEXTS)
    checkpoint = tiny_vla.build_groot_checkpoint(root / "gr00t_n1_7", backbone, CHUNK)
    return {CHECKPOINT: checkpoint, BACKBONE: backbone}


@pytest.fixture
def fake_hub(monkeypatch, tiny_groot):
    """GR00T's two downloads answered with the tiny local models; records the repos asked."""
    from lerobot.policies.groot import groot_n1_7, processor_groot

    asked: list[str] = []

    def snapshot_download(repo_id, **kwargs):
        asked.append(repo_id)
        return str(tiny_groot[repo_id])

    build_processor = processor_groot._build_n1_7_processor

    def build_vlm_processor(model_name):
        asked.append(model_name)
        return build_processor(str(tiny_groot[model_name]))

    monkeypatch.setattr(groot_n1_7, "snapshot_download", snapshot_download)
    monkeypatch.setattr(processor_groot, "_build_n1_7_processor", build_vlm_processor)
    return asked


def test_modality_json_follows_isaac_gr00ts_schema_and_covers_the_vectors(converted):
    info = json.loads((converted / "meta" / "info.json").read_text())
    modality = json.loads((converted / N.GR00T_MODALITY_PATH).read_text())
    assert set(modality) == {"state", "action", "video", "annotation"}
    for part, key in (("state", N.STATE), ("action", N.ACTION_KEY)):
        groups = sorted(modality[part].values(), key=lambda g: g["start"])
        assert all(set(g) <= GROUP_FIELDS for g in groups)
        assert all(g.get("rotation_type", "quaternion") in ROTATION_TYPES for g in groups)
        assert all(g["original_key"] in info["features"] for g in groups)
        # Contiguous, non-overlapping groups that tile the whole vector.
        ranges = [(g["start"], g["end"]) for g in groups if g["original_key"] == key]
        assert ranges[0][0] == 0 and all(a[1] == b[0] for a, b in itertools.pairwise(ranges))
        assert ranges[-1][1] == info["features"][key]["shape"][0] == 7
    assert set(modality["state"]) == {"arm", "gripper"}  # GR00T's single-arm group names
    assert (modality["state"]["arm"]["end"], modality["action"]["gripper"]["absolute"]) == (6, True)
    assert modality["video"] == {
        camera: {"original_key": N.image_key(camera)} for camera in ("front", "hand")
    }
    for camera in modality["video"].values():
        assert info["features"][camera["original_key"]]["dtype"] == "video"
    assert modality["annotation"] == {"human.task_description": {"original_key": "task_index"}}


def test_a_training_step_and_actions_through_lerobots_factories(converted, fake_hub, no_network):
    from lerobot.configs.policies import PreTrainedConfig
    from lerobot.datasets import LeRobotDataset, LeRobotDatasetMetadata
    from lerobot.policies.factory import make_policy, make_pre_post_processors

    meta = LeRobotDatasetMetadata(f"local/{converted.name}", root=converted)
    config = PreTrainedConfig.get_choice_class("groot")(
        chunk_size=CHUNK, n_action_steps=CHUNK, device="cpu", use_bf16=False
    )
    assert (config.base_model_path, config.embodiment_tag) == (CHECKPOINT, "new_embodiment")
    policy = make_policy(config, ds_meta=meta)
    assert fake_hub == [CHECKPOINT]  # built from the (stand-in) 3B checkpoint
    pre, post = make_pre_post_processors(config, dataset_stats=meta.stats)

    dataset = LeRobotDataset(
        f"local/{converted.name}",
        root=converted,
        delta_timestamps={"action": [i / 31.25 for i in range(CHUNK)]},
    )
    batch = next(iter(torch.utils.data.DataLoader(dataset, batch_size=2)))
    processed = pre(batch)
    assert fake_hub == [CHECKPOINT, BACKBONE]  # the VLM's tokenizer and image processor
    # Embodiment "new_embodiment"; 7-d state/action padded to 132 with the padding masked out.
    assert processed["state"].shape == (2, 1, 132) and processed["action"].shape == (2, CHUNK, 132)
    mask = processed["action_mask"]
    assert mask[..., :7].all() and not mask[..., 7:].any()
    assert processed["embodiment_id"].tolist() == [10, 10]
    assert processed["image_grid_thw"].shape[0] == 2 * 2  # both cameras of both samples

    policy.train()
    loss, _ = policy.forward(processed)
    assert torch.isfinite(loss)
    loss.backward()
    torch.optim.AdamW([p for p in policy.parameters() if p.requires_grad], lr=1e-3).step()

    policy.reset()
    observation = {k: v[:1] for k, v in batch.items() if not k.startswith("action")}
    observation["task"] = batch["task"][:1]
    action = post(policy.select_action(pre(observation)))
    assert action.shape == (1, 7) and torch.isfinite(action).all()


@pytest.mark.timeout(1200)  # lerobot-train in a subprocess (tests/conftest.py)
def test_lerobot_train_runs_the_recipe_with_the_hub_replaced_by_a_local_cache(
    converted, tiny_groot, tmp_path
):
    """The unmodified ``lerobot-train`` with ``vla.train_args(..., "groot")`` (the real Hub ids),
    offline, its Hugging Face cache holding the tiny models under those ids."""
    cache = tmp_path / "hub"
    for repo_id, files in tiny_groot.items():
        tiny_vla.seed_hub_cache(cache, repo_id, files)
    args = vla.train_args(converted, "groot")
    args = [a for a in args if not a.startswith(("--policy.chunk_size", "--policy.n_action"))]
    args += [f"--policy.chunk_size={CHUNK}", f"--policy.n_action_steps={CHUNK}"]
    _, trained = tiny_vla.lerobot_train_two_steps(
        [*args, "--policy.use_bf16=false"], tmp_path, hub_cache=cache
    )
    saved = json.loads((trained / "config.json").read_text())
    assert (saved["type"], saved["base_model_path"], saved["chunk_size"]) == (
        "groot",
        CHECKPOINT,
        CHUNK,
    )
    assert saved["embodiment_tag"] == "new_embodiment"
    assert set(saved["input_features"]) >= {N.STATE, N.image_key("front"), N.image_key("hand")}
