"""Each robot's data through the whole pipeline: expert demos -> rmb-convert -> lerobot-train.

The contract tests (test_contract.py) cover each env on its own; these follow a robot's data
through the converter (its ``robot_type``, its per-arm layout) and the unmodified
``lerobot-train``, which evaluates the policy in the robot's own env type during training.
"""

from __future__ import annotations

import json

import pytest

from rmb_lerobot import lerobot_names as N
from rmb_lerobot.envs.registry import ENVS


def _info(dataset) -> dict:
    return json.loads((dataset / "meta" / "info.json").read_text())


@pytest.mark.parametrize(
    ("name", "robot_type", "state_dim"), [("cable", "ur5e", 7), ("xarm7_cable", "xarm7", 8)]
)
def test_lerobot_train_evaluates_in_the_robots_env_type(
    tmp_path, make_expert_dataset, lerobot_cli, name, robot_type, state_dim
):
    """The unmodified lerobot-train on a tiny dataset the cable expert recorded on this robot,
    evaluating in the robot's env type (``--env.type=rmb_xarm7_cable``) during training."""
    entry = ENVS[name]
    dataset = make_expert_dataset(entry.name, tmp_path / "demos", world_idx=(0,), size=32)
    info = _info(dataset)
    assert info["robot_type"] == robot_type
    assert info["features"][N.STATE]["shape"] == [state_dim]  # joints + gripper, RMB's layout

    out = tmp_path / "train"
    train = lerobot_cli(
        "lerobot_train",
        [
            f"--dataset.root={dataset}",
            f"--dataset.repo_id=local/{name}",
            "--policy.type=act",
            "--policy.pretrained_backbone_weights=null",
            "--policy.dim_model=32",
            "--policy.dim_feedforward=64",
            "--policy.chunk_size=4",
            "--policy.n_action_steps=4",
            "--policy.device=cpu",
            "--policy.push_to_hub=false",
            f"--env.type={entry.lerobot_type}",
            "--env.cameras=[front]",
            "--env.image_width=32",
            "--env.image_height=32",
            "--env.episode_length=4",
            "--env_eval_freq=2",
            "--eval.n_episodes=1",
            "--eval.batch_size=1",
            "--steps=2",
            "--batch_size=2",
            "--num_workers=0",
            f"--output_dir={out}",
            "--wandb.enable=false",
        ],
        tmp_path,
    )
    assert train.returncode == 0, train.stderr[-3000:]
    checkpoint = out / "checkpoints" / "last" / "pretrained_model"
    assert (checkpoint / "model.safetensors").exists()
    config = json.loads((checkpoint / "config.json").read_text())
    assert config["output_features"][N.ACTION_KEY]["shape"] == [state_dim]
    assert list((out / "eval").glob("videos_step_*/*/*.mp4")), f"no evaluation in {name}"


def test_dual_arm_demos_convert_with_their_layout(tmp_path, make_expert_dataset):
    """The dual UR5e's 14-number joint vector is per arm (left 6 + gripper, right 6 +
    gripper): the feature names and GR00T's modality.json say so, with the record's arm
    names."""
    dataset = make_expert_dataset("ur5e_dual_cable", tmp_path / "demos", world_idx=(1,), size=16)
    info = _info(dataset)
    assert info["robot_type"] == "ur5e_dual"
    names = info["features"][N.STATE]["names"]
    assert len(names) == 14
    assert (
        names[6] == "measured_joint_pos.gripper_0" and names[13] == "measured_joint_pos.gripper_1"
    )
    modality = json.loads((dataset / N.GR00T_MODALITY_PATH).read_text())
    assert [(name, g["start"], g["end"]) for name, g in modality["state"].items()] == [
        ("left_arm", 0, 6),
        ("left_gripper", 6, 7),
        ("right_arm", 7, 13),
        ("right_gripper", 13, 14),
    ]
    assert list(modality["action"])[:4] == [
        "left_arm",
        "left_gripper",
        "right_arm",
        "right_gripper",
    ]


def test_g1_demos_convert_with_arms_and_hands(tmp_path, make_expert_dataset):
    """The G1's 16-number joint vector is per arm (left 7 joints + hand, right 7 + hand), its
    camera the ``head``: the dataset's robot type, features and modality.json say so."""
    dataset = make_expert_dataset(
        "g1_bottles", tmp_path / "demos", world_idx=(0,), cameras=("head",), size=16
    )
    info = _info(dataset)
    assert info["robot_type"] == "g1"
    names = info["features"][N.STATE]["names"]
    assert len(names) == 16 and info["features"][N.ACTION_KEY]["shape"] == [16]
    assert names[7] == "measured_joint_pos.gripper_0"
    assert names[15] == "measured_joint_pos.gripper_1"
    assert N.image_key("head") in info["features"]
    modality = json.loads((dataset / N.GR00T_MODALITY_PATH).read_text())
    assert [(name, g["start"], g["end"]) for name, g in modality["state"].items()] == [
        ("left_arm", 0, 7),
        ("left_gripper", 7, 8),
        ("right_arm", 8, 15),
        ("right_gripper", 15, 16),
    ]


def test_aloha_demos_convert_with_both_arms_and_their_cameras(tmp_path, make_expert_dataset):
    """ALOHA's 14-number joint vector is per arm (left 6 joints + finger opening, right 6 +
    finger opening), its cameras RMB's (no ``front``): the dataset's robot type, features and
    modality.json say so. (Train and eval: tests/cli/test_aloha_handover_e2e.py.)"""
    dataset = make_expert_dataset(
        "aloha_handover", tmp_path / "demos", world_idx=(0,), cameras=("overhead_cam",), size=16
    )
    info = _info(dataset)
    assert info["robot_type"] == "aloha"
    names = info["features"][N.STATE]["names"]
    assert len(names) == 14 and info["features"][N.ACTION_KEY]["shape"] == [14]
    assert names[6] == "measured_joint_pos.gripper_0"
    assert names[13] == "measured_joint_pos.gripper_1"
    assert N.image_key("overhead_cam") in info["features"]
    modality = json.loads((dataset / N.GR00T_MODALITY_PATH).read_text())
    assert [(name, g["start"], g["end"]) for name, g in modality["state"].items()] == [
        ("left_arm", 0, 6),
        ("left_gripper", 6, 7),
        ("right_arm", 7, 13),
        ("right_gripper", 13, 14),
    ]
