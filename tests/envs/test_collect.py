"""rmb-collect: scripted demonstrations recorded as complete RMB episodes."""

import os
import signal
import time

import numpy as np
import pytest

from rmb_lerobot import find_episodes, open_episode
from rmb_lerobot import keys as K
from rmb_lerobot.cli.collect import main
from rmb_lerobot.envs.collect import CollectConfig, collect
from rmb_lerobot.envs.interrupts import Interrupted, interrupts_raise

SMALL = ["--cameras", "front", "hand", "--image-size", "48", "32"]


def test_collected_episodes_carry_everything_rmb_records(tmp_path, capsys):
    out = tmp_path / "demos"
    code = main(
        ["MujocoUR5eInsert", "--episodes", "2", "--out", str(out), "--world-idx", "1", "4", *SMALL]
    )
    assert code == 0, capsys.readouterr().err
    paths = find_episodes(out)
    assert [p.name for p in paths] == [
        "MujocoUR5eInsert_world1_000.rmb",
        "MujocoUR5eInsert_world4_001.rmb",
    ]
    with open_episode(paths[1]) as ep:
        assert ep.attrs["world_idx"] == 4 and ep.attrs["env"] == "MujocoUR5eInsertEnv"
        assert ep.attrs["task_desc"].startswith("Insert") and ep.attrs["demo_name"] == paths[1].stem
        assert ep.camera_names == ["front", "hand"] and ep.fovy("hand") > 0
        assert ep["reward"][-1] == 1.0  # the expert succeeded
        for key in (
            K.MEASURED_EEF_POSE,
            K.COMMAND_EEF_POSE_REL,
            K.MEASURED_EEF_WRENCH,
            K.COMMAND_JOINT_VEL,
        ):
            assert key in ep
        assert ep["front_rgb_image"][0].shape == (32, 48, 3)
        depth = ep["hand_depth_image"][3]
        assert depth.dtype == np.float32 and 0 < np.median(depth) < 3
        assert ep.fps == pytest.approx(31.25)
    assert "kept 2 episodes (2 successful of 2)" in capsys.readouterr().out


def test_camera_choices_come_from_the_env(tmp_path, capsys):
    """The cameras a run may ask for are the env's: its scene's and its robot's."""
    code = main(["insert", "--episodes", "1", "--out", str(tmp_path), "--cameras", "front", "top"])
    assert code == 2 and not list(tmp_path.iterdir())
    err = capsys.readouterr().err
    assert "--cameras top: not a camera of MujocoUR5eInsert" in err
    assert "its cameras are front left right hand" in err


def test_tactile_flags_say_which_envs_they_fit(tmp_path, capsys):
    """--tactile is MuJoCo's fingertip grid; the TACTO envs record tactile images as cameras,
    sized by --tactile-size, which an env without them refuses."""
    code = main(["TactoSawyerGrasp", "--episodes", "1", "--out", str(tmp_path), "--tactile"])
    assert code == 2 and not list(tmp_path.iterdir())
    assert "records its tactile images as cameras (tactile_left tactile_right" in (
        capsys.readouterr().err
    )
    code = main(["insert", "--episodes", "1", "--out", str(tmp_path), "--tactile-size", "8", "8"])
    assert code == 2 and "MujocoUR5eInsert has no tactile images" in capsys.readouterr().err


def test_parallel_workers_and_single_file_format(tmp_path):
    config = CollectConfig("door", tmp_path, episodes=2, fmt="hdf5", cameras=(), depth=False)
    results = sorted(collect(config, workers=2), key=lambda r: r.index)
    assert [r.success for r in results] == [True, True]
    assert [p.name for p in find_episodes(tmp_path)] == [
        "MujocoUR5eDoor_world0_000.hdf5",
        "MujocoUR5eDoor_world1_001.hdf5",
    ]


def test_an_interrupted_collection_leaves_only_complete_episodes(tmp_path, monkeypatch):
    from rmb_lerobot.envs.experts.insert import InsertExpert

    calls = {"n": 0}
    original = InsertExpert.__call__

    def flaky(self, obs):
        calls["n"] += 1
        if calls["n"] == 70:  # in the middle of the second episode
            raise KeyboardInterrupt
        return original(self, obs)

    monkeypatch.setattr(InsertExpert, "__call__", flaky)
    config = CollectConfig("insert", tmp_path, episodes=3, cameras=("front",), image_size=(32, 32))
    with pytest.raises(KeyboardInterrupt):
        list(collect(config))
    assert [p.name for p in tmp_path.iterdir()] == ["MujocoUR5eInsert_world0_000.rmb"]


def _signal_at_step(monkeypatch, step: int, signum: int) -> None:
    """Send ``signum`` to this process from inside the expert, at its ``step``-th call."""
    from rmb_lerobot.envs.experts.insert import InsertExpert

    calls = {"n": 0}
    original = InsertExpert.__call__

    def signalling(self, obs):
        calls["n"] += 1
        if calls["n"] == step:
            os.kill(os.getpid(), signum)
        return original(self, obs)

    monkeypatch.setattr(InsertExpert, "__call__", signalling)


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_a_signal_stops_the_recording_between_two_steps(tmp_path, monkeypatch, signum):
    _signal_at_step(monkeypatch, 70, signum)  # in the middle of the second episode
    config = CollectConfig("insert", tmp_path, episodes=3, cameras=("front",), image_size=(32, 32))
    run = collect(config)
    with interrupts_raise(), pytest.raises(Interrupted) as info:
        list(run)
    assert info.value.signum == signum and info.value.exit_code == 128 + signum
    assert run.partials_removed == 1
    assert [p.name for p in tmp_path.iterdir()] == ["MujocoUR5eInsert_world0_000.rmb"]


def test_a_signal_while_an_episode_is_committed_keeps_it(tmp_path, monkeypatch):
    from rmb_lerobot.episode.writer import EpisodeWriter

    original = EpisodeWriter.close

    def close_signalled(self):
        os.kill(os.getpid(), signal.SIGTERM)  # noted, raised once the episode is in place
        return original(self)

    monkeypatch.setattr(EpisodeWriter, "close", close_signalled)
    config = CollectConfig("insert", tmp_path, episodes=3, cameras=("front",), image_size=(32, 32))
    run = collect(config)
    with interrupts_raise(), pytest.raises(Interrupted):
        list(run)
    assert run.partials_removed == 0
    (path,) = tmp_path.iterdir()
    with open_episode(path) as ep:
        assert ep["reward"][-1] == 1.0 and len(ep["front_rgb_image"]) == len(ep)


def test_collect_starts_by_removing_what_ended_runs_left(tmp_path, caplog):
    from rmb_lerobot.staging import Staging

    dead = Staging(tmp_path / "MujocoUR5eInsert_world0_000.rmb")
    dead.path.mkdir()
    os.close(dead._lock_fd)  # what the kernel does when the writer's process dies
    dead._lock_fd = None
    with Staging(tmp_path / "other.rmb") as live:
        live.path.mkdir()
        config = CollectConfig("insert", tmp_path, episodes=1, cameras=(), image_size=(32, 32))
        (result,) = collect(config)
        assert not dead.path.exists() and not dead.lock_path.exists()
        assert live.path.exists()  # a live parallel run's temporary stays
    assert dead.path.name in caplog.text
    assert [p.name for p in tmp_path.iterdir()] == [result.path.name]


def test_a_worker_killed_mid_episode_leaves_nothing_once_the_pool_is_gone(tmp_path):
    config = CollectConfig("insert", tmp_path, episodes=20, cameras=("front",), image_size=(32, 32))
    run = collect(config, workers=2)
    next(run)
    deadline = time.monotonic() + 60
    while not (locks := list(tmp_path.glob(".*.lock"))):
        assert time.monotonic() < deadline, "no episode was being recorded"
        time.sleep(0.01)
    pid = int(locks[0].read_text().split()[1])  # the writer's pid, as Staging notes it
    os.kill(pid, signal.SIGKILL)  # no clean-up runs in that worker; its lock dies with it
    run.close()  # terminates the pool, then removes what the killed worker left
    assert run.partials_removed >= 1
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []
    for path in tmp_path.iterdir():
        with open_episode(path) as ep:
            assert len(ep["front_rgb_image"]) == len(ep) > 10


def test_bad_arguments_are_reported(tmp_path, capsys):
    assert main(["MujocoUR5eFly", "--episodes", "1", "--out", str(tmp_path)]) == 2
    assert "unknown RMB environment 'MujocoUR5eFly'" in capsys.readouterr().err
    assert main(["insert", "--episodes", "1", "--out", str(tmp_path), "--world-idx", "7"]) == 2
    assert "--world-idx values must be in 0..5" in capsys.readouterr().err


def test_collected_episodes_read_with_the_original_rmb_loader(tmp_path, read_like_original):
    config = CollectConfig("insert", tmp_path, episodes=1, cameras=("front",), image_size=(32, 24))
    (result,) = collect(config)
    data, attrs = read_like_original(result.path)
    assert attrs["env"] == "MujocoUR5eInsertEnv" and attrs["format"] == "RmbData-Compact"
    assert data["front_rgb_image"].shape == (result.steps, 24, 32, 3)
    assert data["front_depth_image"].shape == (result.steps, 24, 32)
    assert data["measured_eef_pose_rel"].shape == (result.steps, 6)
