"""rmb-convert to-lerobot / from-lerobot on the command line."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
from lerobot.datasets.lerobot_dataset import LeRobotDatasetMetadata

from rmb_lerobot import find_episodes, open_episode
from rmb_lerobot.cli.convert import main


def test_help_lists_the_subcommands():
    result = subprocess.run(
        [sys.executable, "-m", "rmb_lerobot.cli.convert", "--help"], capture_output=True, text=True
    )
    assert result.returncode == 0
    for command in ("switch-format", "to-lerobot", "from-lerobot"):
        assert command in result.stdout


def test_to_and_from_lerobot(demos, tmp_path, capsys):
    dataset = tmp_path / "ds"
    args = ["to-lerobot", str(demos), "--output", str(dataset), "--video-codec", "h264"]
    args += ["--camera-names", "hand", "--depth", "--skip", "2", "--task", "insert it"]
    assert main(args) == 0, capsys.readouterr().err
    assert f"at {dataset}" in capsys.readouterr().out
    meta = LeRobotDatasetMetadata("local/ds", root=dataset)
    assert meta.fps == 15.625 and meta.camera_keys == [
        "observation.images.hand",
        "observation.images.hand_depth",
    ]
    assert list(meta.tasks.index) == ["insert it"]
    rmb = json.loads((dataset / "meta" / "rmb.json").read_text())
    assert rmb["rate"]["skip"] == 2 and rmb["rate"]["dataset"]["fraction"] == "125/8"

    back = tmp_path / "back"
    args = ["from-lerobot", "--root", str(dataset), "--output", str(back), "--format", "hdf5"]
    assert main([*args, "--episodes", "0"]) == 0, capsys.readouterr().err
    (episode,) = find_episodes(back)
    with open_episode(episode) as ep:
        assert ep.fps == pytest.approx(15.625) and ep.camera_names == ["hand"]
        assert ep.attrs["demo_name"] == "MujocoUR5eInsert_world0_000"


def test_errors_exit_2_with_the_reason(demos, tmp_path, capsys):
    out = str(tmp_path / "ds")
    assert main(["to-lerobot", str(demos)]) == 2
    assert "--repo-id or an --output" in capsys.readouterr().err
    assert main(["to-lerobot", str(demos), "--output", out, "--state-keys", "nope"]) == 2
    err = capsys.readouterr().err
    assert "--state-keys names 'nope'" in err and "MujocoUR5eInsert_world0_000.rmb" in err
    assert main(["to-lerobot", str(demos), "--output", out, "--video-codec", "mpeg9"]) == 2
    assert "mpeg9" in capsys.readouterr().err
    assert main(["from-lerobot", "--root", str(tmp_path), "--output", out]) == 2
    assert "no LeRobotDataset here" in capsys.readouterr().err
    bad_map = ["from-lerobot", "--root", str(tmp_path), "--output", out, "--key-map", "x"]
    assert main(bad_map) == 2
    assert "--key-map takes NAME=VALUE" in capsys.readouterr().err
    assert not (tmp_path / "ds").exists()
