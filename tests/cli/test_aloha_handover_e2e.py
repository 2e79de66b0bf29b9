"""ALOHA Handover end to end (issue 25): two-arm expert demos -> rmb-convert -> the unmodified
lerobot-train (a tiny ACT, CPU, nothing downloaded) -> lerobot-eval in ``rmb_aloha_handover``.

Every stage is the command-line tool run as a subprocess by ``rmb-quickstart`` (the README's
main job, ``tests/cli/test_quickstart.py``), here on the bimanual robot: its 14-D action, its
own cameras (no ``front``) and its ``robot_type`` go through every stage.
"""

import json
import re

import pytest

from rmb_lerobot import lerobot_names as N
from rmb_lerobot.cli.quickstart import main

TINY = [
    "--env=MujocoAlohaHandover",
    "--episodes=2",
    "--workers=1",
    "--cameras",
    "overhead_cam",
    "wrist_cam_right",
    "--image-size",
    "32",
    "32",
    "--steps=2",
    "--batch-size=2",
    "--eval-episodes=1",
    "--episode-length=8",
    "--unseen-shift=0",
]


@pytest.mark.timeout(1200)  # lerobot-train + lerobot-eval subprocesses (tests/conftest.py)
def test_aloha_handover_collect_convert_train_eval(tmp_path, capsys):
    out = tmp_path / "qs"

    assert main(["--out", str(out), *TINY]) == 0

    episodes = sorted(p.name for p in (out / "rmb").iterdir())
    assert episodes == [
        "MujocoAlohaHandover_world0_000.rmb",
        "MujocoAlohaHandover_world1_001.rmb",
    ]
    info = json.loads((out / "dataset" / "meta" / "info.json").read_text())
    assert info["robot_type"] == "aloha" and info["total_episodes"] == 2
    assert info["features"][N.ACTION_KEY]["shape"] == [14]  # per arm 6 joints + fingers
    assert {"observation.images.overhead_cam", "observation.images.wrist_cam_right"} <= set(
        info["features"]
    )
    modality = json.loads((out / "dataset" / N.GR00T_MODALITY_PATH).read_text())
    assert [(name, g["start"], g["end"]) for name, g in modality["state"].items()] == [
        ("left_arm", 0, 6),
        ("left_gripper", 6, 7),
        ("right_arm", 7, 13),
        ("right_gripper", 13, 14),
    ]
    policy = out / "train" / "checkpoints" / "last" / "pretrained_model"
    config = json.loads((policy / "config.json").read_text())
    assert config["type"] == "act"
    assert config["output_features"][N.ACTION_KEY]["shape"] == [14]
    eval_info = json.loads((out / "eval" / "eval_info.json").read_text())
    assert eval_info["overall"]["n_episodes"] == 1
    assert all(p.endswith(".mp4") for p in eval_info["overall"]["video_paths"])
    assert re.search(r"success rate: \d+\.\d % \([01]/1 episodes\)", capsys.readouterr().out)
