"""A PyBullet env through the whole pipeline, with its tactile images as cameras.

Scripted Grasp demos (front camera and both DIGIT images) -> ``rmb-convert``'s converter ->
the unmodified ``lerobot-train`` (ACT, which sees ``observation.images.tactile_left/right`` as
two more cameras) -> the unmodified ``lerobot-eval`` in ``--env.type=rmb_pybullet_sawyer_grasp``.
"""

from __future__ import annotations

import json

from rmb_lerobot import lerobot_names as N
from rmb_lerobot.envs.registry import ENVS

CAMERAS = ("front", "tactile_left", "tactile_right")


def test_lerobot_train_then_eval_on_a_pybullet_env_type(tmp_path, make_expert_dataset, lerobot_cli):
    entry = ENVS["pybullet_sawyer_grasp"]
    dataset = make_expert_dataset(entry.name, tmp_path / "demos", cameras=CAMERAS, size=32)
    info = json.loads((dataset / "meta" / "info.json").read_text())
    assert info["robot_type"] == "sawyer"
    for camera in CAMERAS:
        assert info["features"][N.image_key(camera)]["shape"] == [32, 32, 3]
    env_args = [
        f"--env.type={entry.lerobot_type}",
        f"--env.cameras=[{','.join(CAMERAS)}]",
        "--env.image_width=32",
        "--env.image_height=32",
        "--env.episode_length=4",
    ]
    out = tmp_path / "train"
    train = lerobot_cli(
        "lerobot_train",
        [
            f"--dataset.root={dataset}",
            "--dataset.repo_id=local/tacto_grasp",
            "--policy.type=act",
            "--policy.pretrained_backbone_weights=null",
            "--policy.dim_model=32",
            "--policy.dim_feedforward=64",
            "--policy.chunk_size=4",
            "--policy.n_action_steps=4",
            "--policy.device=cpu",
            "--policy.push_to_hub=false",
            *env_args,
            "--env_eval_freq=0",
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
    config = json.loads((checkpoint / "config.json").read_text())
    assert set(config["input_features"]) >= {N.image_key(c) for c in CAMERAS}

    evaluation = lerobot_cli(
        "lerobot_eval",
        [
            f"--policy.path={checkpoint}",
            "--policy.device=cpu",
            *env_args,
            "--eval.n_episodes=1",
            "--eval.batch_size=1",
            f"--output_dir={tmp_path / 'eval'}",
        ],
        tmp_path,
    )
    assert evaluation.returncode == 0, evaluation.stderr[-3000:]
    result = json.loads((tmp_path / "eval" / "eval_info.json").read_text())
    assert result["overall"]["n_episodes"] == 1
