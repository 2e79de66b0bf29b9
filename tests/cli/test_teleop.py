"""rmb-teleop: a headless replay run end to end, and clear errors for bad flags."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

from rmb_lerobot import keys as K
from rmb_lerobot.cli.teleop import main
from rmb_lerobot.episode import EpisodeWriter, find_episodes, open_episode

SMALL = ["--cameras", "front", "--image-size", "48", "32", "--no-depth"]


@pytest.fixture(scope="module")
def log(tmp_path_factory):
    """A 12-step episode of the UR5e cable env in world 2 (the arm swinging its base joint)."""
    from rmb_lerobot.envs.registry import entry_for

    env = entry_for("cable").make(cameras=())
    path = tmp_path_factory.mktemp("log") / "MujocoUR5eCable_world2_000.hdf5"
    try:
        env.reset(seed=0, options={"world_idx": 2})
        with EpisodeWriter(path, env.rmb_attrs()) as writer:
            for t in range(12):
                command = env.command
                command[0] += 0.01 * t
                writer.append(env.rmb_step_data(command))
                env.step(command)
    finally:
        env.close()
    return path


def test_replay_runs_headless_and_records_the_log_again(log, tmp_path):
    out = tmp_path / "replayed"
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "rmb_lerobot.cli.teleop",
            "cable",
            "--input-device",
            "replay",
            "--replay-log",
            str(log),
            "--auto-replay",
            "--save-replay",
            "--replay-repeat-count",
            "2",
            "--no-realtime",
            "--out",
            str(out),
            *SMALL,
        ],
        capture_output=True,
        text=True,
        timeout=180,
        stdin=subprocess.DEVNULL,  # no terminal: --auto-replay needs no keys
    )
    assert result.returncode == 0, result.stderr
    assert f"saved 2 episode(s) in {out}" in result.stdout
    paths = find_episodes(out)
    assert [p.name for p in paths] == [
        "MujocoUR5eCable_world2_000.rmb",
        "MujocoUR5eCable_world2_001.rmb",
    ]
    with open_episode(log) as original, open_episode(paths[1]) as replayed:
        np.testing.assert_allclose(
            replayed[K.COMMAND_JOINT_POS][:], original[K.COMMAND_JOINT_POS][:], atol=1e-9
        )
        assert replayed.camera_names == ["front"]


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["cable", "--input-device", "replay", "--auto-replay"], "needs --replay-log"),
        (["cable", "--keys", "none"], "--keys none works only with --input-device replay"),
        (["cable", "--world-idx", "9"], "--world-idx values must be in 0..5"),
        (["cable", "--auto-replay"], "go with --input-device replay"),
        (["real_ur5e_demo", "--keys", "terminal"], "pass --real-config"),
        (["real_ur5e_demo", "--real-config", "x.yaml", "--num-envs", "2"], "is a real env (one)"),
        (["pybullet_sawyer_grasp", "--no-antialias"], "--no-antialias is a MuJoCo option"),
    ],
)
def test_bad_flags_are_named(argv, message, tmp_path, capsys):
    assert main([*argv, "--out", str(tmp_path / "out"), "--cameras"]) == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_a_device_without_its_module_says_so(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "rmb_lerobot.envs.teleop.spacemouse", None)
    code = main(["cable", "--input-device", "spacemouse", "--out", str(tmp_path), "--cameras"])
    assert code == 2
    assert "spacemouse" in capsys.readouterr().err


def test_without_a_terminal_or_display_the_keyboard_says_where_to_run(
    tmp_path, capsys, monkeypatch
):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    with open(os.devnull) as no_terminal:
        monkeypatch.setattr(sys, "stdin", no_terminal)
        assert main(["cable", "--out", str(tmp_path / "out")]) == 2
    assert "no key source: standard input is not a terminal" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_num_envs_replays_into_three_worlds_with_a_live_view_file(log, tmp_path):
    """Headless parallel collection: one replayed log drives three envs (the log's world 2,
    then 3 and 4); each records its episode, and the live view goes to an .rrd file."""
    pytest.importorskip("rerun", reason="the viz extra (rerun-sdk) is not installed")
    out, rrd = tmp_path / "parallel", tmp_path / "view.rrd"
    argv = ["cable", "--input-device", "replay", "--replay-log", str(log), "--auto-replay"]
    argv += ["--save-replay", "--no-realtime", "--num-envs", "3", "--live-view", str(rrd)]
    assert main([*argv, "--keys", "none", "--out", str(out), *SMALL]) == 0
    paths = find_episodes(out)
    assert [p.name for p in paths] == [
        "MujocoUR5eCable_world2_000.rmb",
        "MujocoUR5eCable_world3_001.rmb",
        "MujocoUR5eCable_world4_002.rmb",
    ]
    for path in paths:
        with open_episode(path) as ep, open_episode(log) as original:
            np.testing.assert_allclose(
                ep[K.COMMAND_JOINT_POS][:], original[K.COMMAND_JOINT_POS][:], atol=1e-9
            )
    assert rrd.stat().st_size > 1000 and not [p for p in tmp_path.iterdir() if "tmp-" in p.name]


def test_num_envs_must_be_positive(tmp_path, capsys):
    assert main(["cable", "--num-envs", "0", "--out", str(tmp_path / "out"), "--cameras"]) == 2
    assert "--num-envs must be >= 1, got 0" in capsys.readouterr().err
