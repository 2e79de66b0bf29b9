"""The rmb-data command line: each subcommand end to end, exit codes and messages."""

import json
import subprocess
import sys

import pytest

from rmb_lerobot import keys as K
from rmb_lerobot import open_episode
from rmb_lerobot.cli.data import main
from rmb_lerobot.episode import switch_format


def test_info_json_and_text(tmp_path, record, capsys):
    record(tmp_path / "a.rmb")
    record(tmp_path / "b.hdf5")
    assert main(["info", str(tmp_path), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["summary"]["episodes"] == 2 and out["summary"]["success_last"] == 2
    assert [e["path"] for e in out["episodes"]] == [
        str(tmp_path / "a.rmb"),
        str(tmp_path / "b.hdf5"),
    ]
    assert out["episodes"][0]["keys"]["measured_joint_pos"]["shape"] == [12, 7]
    assert main(["info", str(tmp_path / "a.rmb"), "--summary-only"]) == 0
    text = capsys.readouterr().out
    assert "1 episode(s)" in text and "success once: 1 / 1" in text and "keys:" not in text


def test_info_exits_1_naming_unreadable_episodes(tmp_path, record, capsys):
    record(tmp_path / "a.rmb")
    (tmp_path / "bad.hdf5").write_bytes(b"junk")
    assert main(["info", str(tmp_path)]) == 1
    captured = capsys.readouterr()
    assert "cannot read" in captured.err and "bad.hdf5" in captured.err
    assert "1 episode(s), 1 unreadable" in captured.out


def test_compare_exit_codes(tmp_path, record, capsys):
    a = record(tmp_path / "a.hdf5")
    b = switch_format(a, tmp_path / "b.rmb")
    assert main(["compare", str(a), str(b)]) == 0
    assert "within tolerances" in capsys.readouterr().out
    assert main(["compare", str(a), str(b), "--min-psnr", "90", "--json"]) == 1
    result = json.loads(capsys.readouterr().out)
    assert not result["ok"]
    assert {r["key"] for r in result["rows"] if not r["ok"]} == {
        "front_rgb_image",
        "hand_rgb_image",
    }
    assert main(["compare", str(a), str(tmp_path / "none.hdf5")]) == 2
    assert "episode not found" in capsys.readouterr().err


def test_refine_refuses_then_overwrites(tmp_path, record, capsys):
    path = record(tmp_path / "a.rmb")
    assert main(["refine", str(path), "--task-desc", "Open the door."]) == 2
    err = capsys.readouterr().err
    assert "rmb-data refine: error" in err and "a.rmb" in err and "--overwrite" in err
    assert main(["refine", str(path), "--task-desc", "Open the door.", "--overwrite"]) == 0
    assert "-> 'Open the door.'" in capsys.readouterr().out
    with open_episode(path) as ep:
        assert ep.attrs[K.ATTR_TASK_DESC] == "Open the door."


def test_add_pointcloud(tmp_path, record, capsys):
    path = record(tmp_path / "a.hdf5")
    args = ["add-pointcloud", str(path), "--camera", "front", "--num-points", "100"]
    assert main([*args, "--image-size", "32", "24", "--rpy-angle", "0", "0", "45"]) == 0
    assert "added front_pointcloud" in capsys.readouterr().out
    with open_episode(path) as ep:
        assert ep["front_pointcloud"].shape == (12, 100, 6)
        assert list(ep.attrs["front_pointcloud_rpy_angle"]) == [0, 0, 45]
    assert main(args) == 2
    assert "already exists" in capsys.readouterr().err
    assert main(["add-pointcloud", str(path), "--camera", "side"]) == 2
    assert "'side_rgb_image'" in capsys.readouterr().err


def test_view_saves_a_recording(tmp_path, record, capsys):
    pytest.importorskip("rerun")
    path = record(tmp_path / "a.rmb")
    rrd = tmp_path / "a.rrd"
    assert main(["view", str(path), "--save", str(rrd), "--image-size", "32", "24"]) == 0
    assert f"wrote {rrd}" in capsys.readouterr().out and rrd.stat().st_size > 0
    assert main(["view", str(path), "--save", str(tmp_path / "a.mp4")]) == 2
    assert ".rrd" in capsys.readouterr().err


def test_tile_videos(eval_output_cli, tmp_path, capsys):
    out = tmp_path / "tiled.mp4"
    assert main(["tile-videos", str(eval_output_cli), "--out", str(out), "--columns", "2"]) == 0
    assert "3 rollouts, 2 successful" in capsys.readouterr().out and out.stat().st_size > 0
    assert main(["tile-videos", str(eval_output_cli), "--out", str(out)]) == 2
    assert "--overwrite" in capsys.readouterr().err


@pytest.fixture
def eval_output_cli(tmp_path):
    """Three rollouts as lerobot-eval leaves them (videos + eval_info.json)."""
    import numpy as np
    from lerobot.utils.io_utils import write_video

    videos = tmp_path / "eval" / "videos" / "rmb_ur5e_insert_0"
    videos.mkdir(parents=True)
    paths = []
    for k in range(3):
        write_video(
            str(videos / f"eval_episode_{k}.mp4"), [np.zeros((32, 32, 3), np.uint8)] * 4, 10
        )
        paths.append(str(videos / f"eval_episode_{k}.mp4"))
    metrics = {"successes": [True, False, True], "video_paths": paths}
    info = {"per_task": [{"task_group": "rmb_ur5e_insert", "task_id": 0, "metrics": metrics}]}
    (tmp_path / "eval" / "eval_info.json").write_text(json.dumps(info))
    return tmp_path / "eval"


def test_help_lists_every_subcommand():
    result = subprocess.run(
        [sys.executable, "-m", "rmb_lerobot.cli.data", "--help"], capture_output=True, text=True
    )
    assert result.returncode == 0
    for command in ("info", "compare", "refine", "add-pointcloud", "view", "tile-videos"):
        assert command in result.stdout


def test_interrupted_add_pointcloud_leaves_the_episode_as_it_was(
    tmp_path, record, monkeypatch, capsys
):
    import h5py

    path = record(tmp_path / "a.rmb")
    before = {p.name: p.read_bytes() for p in path.iterdir()}

    def interrupt(*args, **kwargs):
        raise KeyboardInterrupt  # Ctrl-C while the new file is being written

    monkeypatch.setattr(h5py.Group, "create_dataset", interrupt)
    assert main(["add-pointcloud", str(path), "--camera", "front"]) == 130
    assert "interrupted (SIGINT)" in capsys.readouterr().err
    assert {p.name: p.read_bytes() for p in path.iterdir()} == before  # no temporaries either
