"""The README's main job: collect -> convert -> lerobot-train (ACT) -> lerobot-eval, tiny."""

import json
import re

import pytest

from rmb_lerobot.cli.quickstart import main, parse_args, pipeline

TINY = [
    "--episodes=2",
    "--workers=1",
    "--cameras",
    "front",
    "--image-size",
    "32",
    "32",
    "--steps=2",
    "--batch-size=2",
    "--eval-episodes=1",
    "--episode-length=8",
]


def test_the_pipeline_is_the_four_unmodified_command_line_tools(tmp_path):
    stages = pipeline(parse_args(["--out", str(tmp_path), "--env", "MujocoUR5eDoor"]))

    assert [stage.name for stage in stages] == [
        "rmb-collect",
        "rmb-convert",
        "lerobot-train",
        "lerobot-eval",
    ]
    collect, convert, train, evaluate = stages
    assert str(collect).startswith("rmb-collect MujocoUR5eDoor --episodes=30")
    assert str(convert).startswith(f"rmb-convert to-lerobot {tmp_path / 'rmb'}")
    for stage in (train, evaluate):  # trained and evaluated on the same env type and inputs
        assert {
            "--env.type=rmb_ur5e_door",
            "--env.cameras=[front,hand]",
            "--env.image_width=64",
            "--env.image_height=64",
        } <= set(stage.args)
    assert {"--policy.type=act", "--policy.pretrained_backbone_weights=null"} <= set(train.args)
    assert f"--policy.path={tmp_path}/train/checkpoints/last/pretrained_model" in evaluate.args


def test_an_unknown_env_is_refused_before_anything_runs(tmp_path):
    with pytest.raises(ValueError, match="unknown RMB environment 'MujocoUR5eNope'"):
        main(["--out", str(tmp_path / "qs"), "--env", "MujocoUR5eNope"])
    assert not (tmp_path / "qs").exists()


def test_main_job_end_to_end_at_a_tiny_size(tmp_path, capsys):
    out = tmp_path / "qs"

    assert main(["--out", str(out), *TINY]) == 0

    printed = capsys.readouterr().out
    assert re.search(r"success rate: \d+\.\d % \([01]/1 episodes\)", printed)
    episodes = sorted(p.name for p in (out / "rmb").iterdir())
    assert episodes == ["MujocoUR5eInsert_world0_000.rmb", "MujocoUR5eInsert_world1_001.rmb"]
    info = json.loads((out / "dataset" / "meta" / "info.json").read_text())
    assert info["total_episodes"] == 2 and "observation.images.front" in info["features"]
    policy = out / "train" / "checkpoints" / "last" / "pretrained_model"
    assert json.loads((policy / "config.json").read_text())["type"] == "act"
    eval_info = json.loads((out / "eval" / "eval_info.json").read_text())
    assert eval_info["overall"]["n_episodes"] == 1
    assert all(p.endswith(".mp4") for p in eval_info["overall"]["video_paths"])
    assert f"dataset:      {out / 'dataset'}" in printed
