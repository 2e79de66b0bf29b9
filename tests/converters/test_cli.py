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


# Issue 30: Hub failures in one line, HF_HUB_OFFLINE honoured, encoders quiet unless --verbose.


def test_a_missing_dataset_offline_is_a_clear_error_without_network(
    tmp_path, monkeypatch, capsys, no_network
):
    monkeypatch.setenv("HF_HUB_OFFLINE", "1")
    code = main(["from-lerobot", "nobody/not_here", "--output", str(tmp_path / "out")])
    assert code == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and "Traceback" not in error
    assert "dataset nobody/not_here is not in $HF_LEROBOT_HOME and HF_HUB_OFFLINE is set" in error
    assert "--root" in error and not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    ("failure", "why"),
    [
        ("connect", "the Hub could not be reached (ConnectError); check the network"),
        ("404", "repository not found (404); check the id"),
    ],
)
def test_a_hub_failure_is_one_line_saying_what_why_and_what_to_do(
    tmp_path, monkeypatch, capsys, failure, why
):
    import httpx
    from huggingface_hub.errors import RepositoryNotFoundError

    from rmb_lerobot.converters import lerobot_to_rmb

    def fail(repo_id, root):
        request = httpx.Request("GET", f"https://huggingface.co/api/datasets/{repo_id}")
        if failure == "connect":
            raise httpx.ConnectError("[Errno -3] Temporary failure in name resolution")
        response = httpx.Response(404, request=request)
        raise RepositoryNotFoundError("404 Client Error. Repository Not Found", response=response)

    monkeypatch.setattr(lerobot_to_rmb, "open_dataset", fail)
    code = main(["from-lerobot", "someone/gone", "--output", str(tmp_path / "out")])
    assert code == 1
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and "Traceback" not in error
    assert error.startswith(
        f"rmb-convert: error: downloading dataset someone/gone from the Hub failed: {why}"
    )


def test_a_failed_push_is_one_line_and_keeps_the_dataset(demos, tmp_path, monkeypatch, capsys):
    import httpx

    from rmb_lerobot import converters

    def fail(*args, **kwargs):
        request = httpx.Request("POST", "https://huggingface.co/api/repos/create")
        raise httpx.HTTPStatusError("401", request=request, response=httpx.Response(401))

    monkeypatch.setattr(converters, "push_dataset", fail)
    args = ["to-lerobot", str(demos), "--repo-id", "someone/x", "--output", str(tmp_path / "ds")]
    code = main([*args, "--video-codec", "h264", "--camera-names", "hand", "--push-to-hub"])
    assert code == 1
    error = capsys.readouterr().err  # the conversion's progress bars, then one line
    assert "Traceback" not in error and error.splitlines()[-1].startswith("rmb-convert: error: ")
    assert "rmb-convert: error:" not in "\n".join(error.splitlines()[:-1])
    assert "pushing someone/x to the Hub failed: not authorised (401); log in with a token" in error
    assert f"kept at {tmp_path / 'ds'}" in error and (tmp_path / "ds" / "meta").is_dir()


@pytest.mark.parametrize("verbose", [False, True], ids=["quiet", "verbose"])
def test_the_av1_encoder_is_quiet_unless_verbose(demos, tmp_path, monkeypatch, capfd, verbose):
    monkeypatch.delenv("SVT_LOG", raising=False)  # restored (unset) after the test
    args = ["to-lerobot", str(demos), "--output", str(tmp_path / "ds"), "--camera-names", "hand"]
    code = main([*args, "--video-codec", "libsvtav1", *(["--verbose"] if verbose else [])])
    assert code == 0
    assert ("Svt[info]" in capfd.readouterr().err) == verbose
