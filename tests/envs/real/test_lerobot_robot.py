"""The LeRobot plugins of the real arms (``rmb_ur5e``, ``rmb_xarm7``, ``rmb_ur5e_dual``, the
``rmb_scripted`` teleoperator) against the MuJoCo twins.

In-process: registration and LeRobot's own device-class lookup, the features, an observation
and action round trip, refusals by the safety layer (NaN, missing keys), the watchdog resume,
the dual arm stopping both arms. Then one test runs LeRobot's unmodified CLIs as a lab would:
``lerobot-record`` two episodes with the scripted teleoperator, ``lerobot-replay`` one,
``lerobot-train`` a tiny ACT on the recording (its loss must fall), ``lerobot-rollout
--strategy.type=base`` that trained policy, and ``rmb-convert from-lerobot`` + ``rmb-data
info`` on the recording. Offline, loopback only, HF_LEROBOT_HOME and the calibration
directory in tmp.
"""

from __future__ import annotations

import json
import logging
import math
import re
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest
from lerobot.robots import RobotConfig, make_robot_from_config
from lerobot.teleoperators import TeleoperatorConfig, make_teleoperator_from_config

import lerobot_env_rmb  # noqa: F401  (registers the types, as LeRobot's plugin loader does)
from rmb_lerobot.envs.real.cameras import TwinCameraConfig
from rmb_lerobot.envs.real.errors import JumpTooLarge, NonFiniteCommand
from rmb_lerobot.envs.real.lerobot_devices import (
    RmbScripted,
    RmbScriptedConfig,
    RmbUR5e,
    RmbUR5eConfig,
    RmbUR5eDual,
    RmbUR5eDualConfig,
    RmbXarm7,
    RmbXarm7Config,
)
from rmb_lerobot.envs.real.lerobot_devices.config import RmbArmConfig
from rmb_lerobot.envs.real.lerobot_devices.features import action_keys, home_vector
from rmb_lerobot.envs.real.testing import lerobot_cli_command, lerobot_cli_env
from rmb_lerobot.envs.robots import UR5E, XARM7

UR5E_KEYS = [f"{j}.pos" for j in UR5E.arms[0].joints] + ["gripper.pos"]
SIZE = (24, 32)  # (H, W): small renders on a loaded machine


def twin_camera(use_depth: bool = False) -> TwinCameraConfig:
    return TwinCameraConfig(height=SIZE[0], width=SIZE[1], fps=30, use_depth=use_depth)


@pytest.fixture
def ur5e(tmp_path):
    robot = make_robot_from_config(
        RmbUR5eConfig(calibration_dir=tmp_path, cameras={"front": twin_camera(use_depth=True)})
    )
    robot.connect()
    yield robot
    if robot.is_connected:
        robot.disconnect()


def joints_of(obs: dict) -> np.ndarray:
    return np.array([obs[k] for k in obs if k.endswith(".pos")])


# ------------------------------------------------------------------ registration, features
def test_types_are_registered_and_found_by_lerobots_lookup(tmp_path):
    assert {"rmb_ur5e", "rmb_xarm7", "rmb_ur5e_dual"} <= set(RobotConfig.get_known_choices())
    assert "rmb_scripted" in TeleoperatorConfig.get_known_choices()
    # make_*_from_config: LeRobot's own fallback (make_device_from_device_class), which looks
    # the device class up in the config module's parent package.
    built = {
        RmbUR5e: RmbUR5eConfig(calibration_dir=tmp_path),
        RmbXarm7: RmbXarm7Config(calibration_dir=tmp_path),
        RmbUR5eDual: RmbUR5eDualConfig(calibration_dir=tmp_path),
    }
    for cls, config in built.items():
        robot = make_robot_from_config(config)
        assert type(robot) is cls and robot.cameras == {} and not robot.is_connected
    teleop = make_teleoperator_from_config(RmbScriptedConfig(calibration_dir=tmp_path))
    assert type(teleop) is RmbScripted


def test_features_name_joints_and_gripper_pos_in_observation_and_action(tmp_path):
    cams = {"front": twin_camera(use_depth=True), "hand": twin_camera()}
    robot = RmbUR5e(RmbUR5eConfig(calibration_dir=tmp_path, cameras=cams))
    assert list(robot.action_features) == UR5E_KEYS
    assert robot.observation_features == {
        **dict.fromkeys(UR5E_KEYS, float),
        "front": (*SIZE, 3),
        "front_depth": (*SIZE, 1),
        "hand": (*SIZE, 3),
    }
    assert set(robot.cameras) == {"front", "hand"}
    xarm = RmbXarm7(RmbXarm7Config(calibration_dir=tmp_path))
    assert list(xarm.action_features) == [f"joint{i}.pos" for i in range(1, 8)] + ["gripper.pos"]
    assert list(xarm.observation_features) == list(xarm.action_features)

    dual = RmbUR5eDual(
        RmbUR5eDualConfig(
            calibration_dir=tmp_path,
            left_arm_config=RmbArmConfig(cameras={"hand": twin_camera()}),
            cameras={"front": twin_camera()},
        )
    )
    expected = [f"{side}_{k}" for side in ("left", "right") for k in UR5E_KEYS]
    assert list(dual.action_features) == expected
    assert dual.observation_features == {
        **dict.fromkeys(expected, float),
        "left_hand": (*SIZE, 3),
        "front": (*SIZE, 3),
    }
    assert set(dual.cameras) == {"left_hand", "front"}
    # The scripted teleoperator emits exactly the robots' action keys (lerobot-record needs
    # every one of them).
    for robot_type, device in (("rmb_ur5e", robot), ("rmb_xarm7", xarm), ("rmb_ur5e_dual", dual)):
        script = RmbScripted(RmbScriptedConfig(robot=robot_type, calibration_dir=tmp_path))
        assert list(script.action_features) == list(device.action_features)
        assert list(script.action_at(1.0)) == list(device.action_features)
    # Only joints and grippers end in .pos/.vel (lerobot-rollout feeds a policy only those).
    for device in (robot, xarm, dual):
        for key, ft in device.observation_features.items():
            assert key.endswith(".pos") == (ft is float) and not key.endswith(".vel")


def test_config_needs_a_host_for_the_sdk_and_loopback_for_the_twin():
    with pytest.raises(ValueError, match="no default lab address"):
        RmbUR5eConfig(driver="sdk")
    with pytest.raises(ValueError, match="loopback"):
        RmbXarm7Config(driver="sim", host="192.168.1.10")
    with pytest.raises(ValueError, match="driver must be one of"):
        RmbUR5eConfig(driver="rtde")
    with pytest.raises(ValueError, match="right arm"):
        RmbUR5eDualConfig(right_arm_config=RmbArmConfig(driver="sdk"))
    with pytest.raises(ValueError, match="need driver 'sim'"):
        RmbUR5eConfig(driver="sdk", host="10.0.0.2", cameras={"front": twin_camera()})
    assert RmbUR5eConfig(driver="sdk", host="10.0.0.2").host == "10.0.0.2"  # nothing connects
    assert RmbUR5eConfig().resolved_host("x") == "127.0.0.1"


def test_scripted_wave_stays_slow_and_holds_home(tmp_path):
    wave = RmbScripted(RmbScriptedConfig(robot="rmb_xarm7", calibration_dir=tmp_path))
    values = np.array([list(wave.action_at(t).values()) for t in np.arange(0, 4, 0.02)])
    home = home_vector("rmb_xarm7")
    assert np.allclose(values[0], home)
    joint_speed = np.abs(np.diff(values[:, :-1], axis=0)).max() / 0.02
    assert 0 < joint_speed <= 2 * math.pi * math.radians(5.0) / 4.0 + 1e-6
    assert values[:, -1].max() == pytest.approx(XARM7.arms[0].gripper.closed / 2, abs=1.0)
    hold = RmbScripted(
        RmbScriptedConfig(robot="rmb_ur5e_dual", motion="hold", calibration_dir=tmp_path)
    )
    assert list(hold.action_at(3.0).values()) == pytest.approx(home_vector("rmb_ur5e_dual"))
    assert len(action_keys("rmb_ur5e_dual")) == 14


# ------------------------------------------------------------------ on the twin, in process
def test_observation_action_round_trip_on_the_twin(ur5e, tmp_path):
    obs = ur5e.get_observation()
    assert list(obs) == list(ur5e.observation_features)
    assert obs["front"].shape == (*SIZE, 3) and obs["front"].dtype == np.uint8
    assert obs["front_depth"].shape == (*SIZE, 1) and obs["front_depth"].dtype == np.uint16
    # mm, 0 where nothing is in range (the background); the arm and floor are metres away.
    assert 0 < obs["front_depth"].max() < 10_000
    measured = joints_of(obs)
    assert np.allclose(measured[:-1], UR5E.arms[0].home, atol=1e-3)

    # Holding the measured position is sent as it is.
    sent = ur5e.send_action({k: obs[k] for k in ur5e.action_features})
    assert list(sent) == UR5E_KEYS
    assert np.allclose(list(sent.values())[:-1], measured[:-1], atol=1e-6)

    # The scripted teleoperator's stream moves the arm; what was sent is what the layer let
    # through: a target 1 rad away in one 1/30 s step is clamped to 2 v_lim dt (0.22 rad).
    script = RmbScripted(RmbScriptedConfig(calibration_dir=tmp_path))
    script.connect()
    for _ in range(20):
        ur5e.send_action(script.get_action())
        time.sleep(1 / 30)
    script.disconnect()
    far = {k: obs[k] for k in UR5E_KEYS}
    far["shoulder_pan_joint.pos"] += 1.0
    before = ur5e.get_observation()["shoulder_pan_joint.pos"]
    sent = ur5e.send_action(far)
    reach = 2 * math.radians(191) / 30
    assert sent["shoulder_pan_joint.pos"] == pytest.approx(before + reach, abs=0.02)
    assert sent["shoulder_pan_joint.pos"] < far["shoulder_pan_joint.pos"] - 0.5


def test_xarm7_round_trip_on_its_twin(tmp_path):
    robot = RmbXarm7(RmbXarm7Config(calibration_dir=tmp_path))
    script = RmbScripted(RmbScriptedConfig(robot="rmb_xarm7", calibration_dir=tmp_path))
    with robot:
        obs = robot.get_observation()
        assert list(obs) == list(robot.action_features)
        assert np.allclose(joints_of(obs)[:-1], XARM7.arms[0].home, atol=1e-3)
        script.connect()
        for _ in range(15):
            sent = robot.send_action(script.get_action())
            time.sleep(1 / 30)
        assert list(sent) == list(robot.action_features)
        assert not np.allclose(joints_of(robot.get_observation())[:-1], XARM7.arms[0].home)
    assert not robot.is_connected


def test_nan_and_jump_actions_are_refused_and_stop_the_arm(ur5e):
    obs = ur5e.get_observation()
    action = {k: obs[k] for k in UR5E_KEYS}
    driver = ur5e.real.layers[0].driver
    stops = []
    real_stop = driver.stop
    driver.stop = lambda: (stops.append(time.monotonic()), real_stop())[1]
    bad = {**action, "elbow_joint.pos": float("nan")}
    with pytest.raises(NonFiniteCommand, match="elbow_joint"):
        ur5e.send_action(bad)
    with pytest.raises(JumpTooLarge):
        ur5e.send_action({**action, "wrist_1_joint.pos": action["wrist_1_joint.pos"] + 2.0})
    with pytest.raises(KeyError, match=r"gripper\.pos"):
        ur5e.send_action({k: v for k, v in action.items() if k != "gripper.pos"})
    driver.stop = real_stop
    assert len(stops) >= 3  # each refusal stopped the arm before raising
    assert np.allclose(joints_of(ur5e.get_observation())[:-1], joints_of(obs)[:-1], atol=1e-3)
    # The stream goes on after a refusal.
    assert ur5e.send_action(action)["elbow_joint.pos"] == pytest.approx(action["elbow_joint.pos"])


def test_a_pause_in_the_stream_stops_the_arm_and_the_next_action_resumes(ur5e, caplog):
    action = {k: v for k, v in ur5e.get_observation().items() if k in UR5E_KEYS}
    ur5e.send_action(action)
    layer = ur5e.real.layers[0]
    deadline = time.monotonic() + 5.0
    while not layer.watchdog.tripped and time.monotonic() < deadline:
        time.sleep(0.05)
    assert layer.watchdog.tripped  # LeRobot saving an episode: no actions for a while
    with caplog.at_level(logging.WARNING):
        ur5e.send_action(action)
    assert "resuming from where the arm stands" in caplog.text
    assert not layer.watchdog.tripped


def test_dual_arm_round_trip_and_a_refusal_stops_both_arms(tmp_path):
    dual = RmbUR5eDual(RmbUR5eDualConfig(calibration_dir=tmp_path))
    dual.connect()
    try:
        obs = dual.get_observation()
        assert list(obs) == list(dual.action_features)
        action = {k: obs[k] for k in dual.action_features}
        sent = dual.send_action(action)
        assert list(sent) == list(dual.action_features)
        stopped = []
        for side, arm in (("left", dual.left_arm), ("right", dual.right_arm)):
            arm_stop = arm.stop
            arm.stop = lambda side=side, arm_stop=arm_stop: (stopped.append(side), arm_stop())
        with pytest.raises(NonFiniteCommand) as refused:
            dual.send_action({**action, "right_wrist_3_joint.pos": float("inf")})
        assert sorted(stopped) == ["left", "right"]
        assert "right arm" in "".join(refused.value.__notes__)
    finally:
        dual.disconnect()
    assert not dual.is_connected


# ------------------------------------------------------------------ LeRobot's CLIs
TINY_ACT = [
    "--policy.type=act",
    "--policy.device=cpu",
    "--policy.push_to_hub=false",
    "--policy.pretrained_backbone_weights=null",  # no download
    "--policy.dim_model=32",
    "--policy.dim_feedforward=64",
    "--policy.n_heads=2",
    "--policy.n_encoder_layers=1",
    "--policy.n_decoder_layers=1",
    "--policy.chunk_size=4",
    "--policy.n_action_steps=4",
    "--policy.use_vae=false",
    "--policy.optimizer_lr=3e-3",
]
TRAIN_STEPS = 20

CLI_TIMEOUT_S = 600  # one CLI: ~25 s to start on an idle 2-core machine, minutes when loaded
CAMERAS = (
    f"{{front: {{type: rmb_twin, width: {SIZE[1]}, height: {SIZE[0]}, fps: 30, use_depth: false}}}}"
)
ROBOT = ["--robot.type=rmb_ur5e", "--robot.driver=sim", f"--robot.cameras={CAMERAS}"]


def _start(script: str, args: list[str], tmp_path: Path, log: str) -> subprocess.Popen:
    """Start ``lerobot-<script>`` (the console script installed beside this interpreter)."""
    with open(tmp_path / log, "w") as out:  # the child keeps its own descriptor
        return subprocess.Popen(
            [*lerobot_cli_command(script), *args],
            cwd=tmp_path,
            env=lerobot_cli_env(tmp_path),
            stdout=out,
            stderr=subprocess.STDOUT,
        )


def _finish(process: subprocess.Popen, tmp_path: Path, log: str) -> str:
    try:
        process.wait(timeout=CLI_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()
    text = (tmp_path / log).read_text()
    assert process.returncode == 0, f"{log}: exit {process.returncode}\n{text[-4000:]}"
    return text


@pytest.mark.timeout(1800)  # four LeRobot CLIs, on a loaded machine
def test_lerobot_record_replay_rollout_and_convert_on_the_twin(tmp_path, capsys):
    dataset = tmp_path / "dataset"
    record = _start(
        "record",
        [
            *ROBOT,
            "--teleop.type=rmb_scripted",
            "--dataset.repo_id=local/rmb_twin",
            f"--dataset.root={dataset}",
            "--dataset.num_episodes=2",
            "--dataset.episode_time_s=2",
            "--dataset.reset_time_s=0.5",
            "--dataset.fps=30",
            "--dataset.single_task=wave",
            "--dataset.push_to_hub=false",
            "--dataset.no_stamp=true",
            "--play_sounds=false",
        ],
        tmp_path,
        "record.log",
    )
    _finish(record, tmp_path, "record.log")
    info = json.loads((dataset / "meta" / "info.json").read_text())
    assert info["robot_type"] == "rmb_ur5e" and info["total_episodes"] == 2
    features = info["features"]
    assert features["action"]["names"] == UR5E_KEYS == features["observation.state"]["names"]
    assert features["observation.images.front"]["shape"] == [*SIZE, 3]
    assert info["total_frames"] >= 2 * 10  # 2 s at 30 fps each, frames dropped when loaded

    # Replay episode 0 and run a policy while the recording is converted in this process.
    replay = _start(
        "replay",
        [
            *ROBOT[:2],
            "--dataset.repo_id=local/rmb_twin",
            f"--dataset.root={dataset}",
            "--dataset.episode=0",
            "--play_sounds=false",
        ],
        tmp_path,
        "replay.log",
    )
    train = _start(
        "train",
        [
            "--dataset.repo_id=local/rmb_twin",
            f"--dataset.root={dataset}",
            *TINY_ACT,
            f"--steps={TRAIN_STEPS}",
            "--batch_size=8",
            f"--save_freq={TRAIN_STEPS}",
            "--log_freq=5",
            "--num_workers=0",
            "--seed=0",
            f"--output_dir={tmp_path / 'train'}",
            "--wandb.enable=false",
        ],
        tmp_path,
        "train.log",
    )
    # Loss per logged step (LeRobot prints each log line to the console and its log file).
    trained = _finish(train, tmp_path, "train.log")
    losses = dict(re.findall(r"step:(\S+) .*?loss:([0-9.]+)", trained))
    curve = [float(v) for v in losses.values()]
    assert len(curve) == TRAIN_STEPS // 5 and curve[-1] < curve[0], losses  # it learned
    policy = tmp_path / "train" / "checkpoints" / "last" / "pretrained_model"
    rollout = _start(
        "rollout",
        [
            "--strategy.type=base",
            f"--policy.path={policy}",
            *ROBOT,
            "--task=wave",
            "--duration=3",
            "--fps=30",
            "--device=cpu",
        ],
        tmp_path,
        "rollout.log",
    )
    from rmb_lerobot.cli.convert import main as convert
    from rmb_lerobot.cli.data import main as data

    episodes = tmp_path / "rmb"
    assert convert(["from-lerobot", "--root", str(dataset), "--output", str(episodes)]) == 0
    capsys.readouterr()
    assert data(["info", str(episodes)]) == 0
    described = capsys.readouterr().out
    assert "2 episode(s)" in described and "env: 'rmb_ur5e'" in described
    assert "measured_joint_pos" in described and "front_rgb_image" in described

    replayed = _finish(replay, tmp_path, "replay.log")
    assert "Replaying episode" in replayed and "Traceback" not in replayed
    rolled = _finish(rollout, tmp_path, "rollout.log")
    assert "Duration limit reached" in rolled and "Rollout finished" in rolled
    assert "Returning robot to initial position" in rolled and "Traceback" not in rolled
