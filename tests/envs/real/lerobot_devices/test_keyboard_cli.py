"""Cartesian teleoperation through LeRobot's unmodified CLIs, headless, on the UR5e twin.

``lerobot-teleoperate`` and ``lerobot-record`` run with ``--robot.action_space=ee_velocity``
and ``--teleop.type=rmb_keyboard``; their standard input is a pseudo-terminal this test types
into, so the teleoperator's terminal reader is the real one (cbreak mode, escape sequences).
Offline, loopback only, HF_LEROBOT_HOME and the calibration directory in tmp.
"""

from __future__ import annotations

import ast
import json
import os
import pty
import re
import subprocess
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from rmb_lerobot.envs.real.lerobot_devices.ee_action import build_arm_kinematics
from rmb_lerobot.envs.real.lerobot_devices.features import EE_VELOCITY_KEYS
from rmb_lerobot.envs.real.testing import lerobot_cli_command, lerobot_cli_env
from rmb_lerobot.envs.robots import UR5E

CLI_TIMEOUT_S = 600  # one CLI: ~25 s to start on an idle 2-core machine, minutes when loaded
FPS = 30
STEP_M = 0.01  # RMB's keyboard step
ROBOT = [
    "--robot.type=rmb_ur5e",
    "--robot.driver=sim",
    "--robot.action_space=ee_velocity",
    f"--robot.command_duration_s={1 / FPS}",
]
TELEOP = ["--teleop.type=rmb_keyboard", f"--teleop.fps={FPS}"]
TCP_LOG = re.compile(r"end effector (starts|ends) at (\[[^\]]*\]) m")


def _env(tmp_path: Path) -> dict[str, str]:
    env = lerobot_cli_env(tmp_path)
    env.pop("DISPLAY", None)  # headless: the terminal is the only keyboard
    env.pop("WAYLAND_DISPLAY", None)
    return env


def run_typing(script: str, args: list[str], tmp_path: Path, keys: list[tuple[str, float]]) -> str:
    """Run ``lerobot-<script>`` with a pty as standard input; once the robot has connected,
    type each ``(text, pause_s)`` and wait for the exit.

    Returns:
        The combined output.
    """
    command = lerobot_cli_command(script)
    log = tmp_path / f"{script}.log"
    master, slave = pty.openpty()
    try:
        with open(log, "w") as out:
            process = subprocess.Popen(
                [*command, *args],
                cwd=tmp_path,
                env=_env(tmp_path),
                stdin=slave,
                stdout=out,
                stderr=subprocess.STDOUT,
                start_new_session=True,
            )
        os.close(slave)
        deadline = time.monotonic() + CLI_TIMEOUT_S
        while "end effector starts at" not in log.read_text():
            assert process.poll() is None, f"{script} exited early:\n{log.read_text()[-4000:]}"
            assert time.monotonic() < deadline, f"{script} never connected"
            time.sleep(0.2)
        for text, pause in keys:
            os.write(master, text.encode())
            time.sleep(pause)
        try:
            process.wait(timeout=CLI_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()
    finally:
        os.close(master)
    text = log.read_text()
    assert process.returncode == 0, f"{script}: exit {process.returncode}\n{text[-4000:]}"
    assert "Traceback" not in text, text[-4000:]
    return text


def tcp_moves(text: str) -> np.ndarray:
    found = {when: np.array(ast.literal_eval(xyz)) for when, xyz in TCP_LOG.findall(text)}
    assert set(found) == {"starts", "ends"}, text[-4000:]
    return found["ends"] - found["starts"]


@pytest.mark.timeout(900)
def test_lerobot_teleoperate_moves_the_tcp_the_way_the_keys_say(tmp_path):
    # 8 x W (+x), 3 x Q (+z, RMB's key; LeRobot's teleoperate has no keys of its own).
    keys = [("w", 0.1)] * 8 + [("q", 0.1)] * 3
    text = run_typing(
        "teleoperate", [*ROBOT, *TELEOP, f"--fps={FPS}", "--teleop_time_s=6"], tmp_path, keys
    )
    moved = tcp_moves(text)
    assert moved == pytest.approx([8 * STEP_M, 0.0, 3 * STEP_M], abs=0.015)
    assert moved[0] > 0.05 and moved[2] > 0.015


@pytest.mark.timeout(900)
def test_lerobot_record_stores_the_twist_and_lerobot_keys_still_work(tmp_path):
    dataset = tmp_path / "dataset"
    args = [
        *ROBOT,
        *TELEOP,
        "--dataset.repo_id=local/rmb_keyboard",
        f"--dataset.root={dataset}",
        "--dataset.num_episodes=1",
        "--dataset.episode_time_s=120",
        "--dataset.reset_time_s=0",
        f"--dataset.fps={FPS}",
        "--dataset.single_task=push",
        "--dataset.push_to_hub=false",
        "--dataset.no_stamp=true",
        "--dataset.video=false",
        "--play_sounds=false",
    ]
    # 6 x D (-y), then "n": LeRobot's "next episode" key, forwarded by rmb_keyboard to
    # LeRobot's own terminal listener, ends the 120 s episode early.
    text = run_typing("record", args, tmp_path, [("d", 0.1)] * 6 + [("", 3.0), ("n", 0.0)])
    assert "Exiting loop" in text  # LeRobot's listener got the forwarded key
    info = json.loads((dataset / "meta" / "info.json").read_text())
    assert info["total_episodes"] == 1
    features = info["features"]
    assert features["action"]["names"] == [*EE_VELOCITY_KEYS, "gripper.pos"]
    joints = [f"{j}.pos" for j in UR5E.arms[0].joints] + ["gripper.pos"]
    assert features["observation.state"]["names"] == joints
    frames = pd.concat(pd.read_parquet(p) for p in sorted((dataset / "data").rglob("*.parquet")))
    actions = np.stack(frames["action"].to_numpy())
    assert len(actions) < 120 * FPS / 2  # ended by the key, not the clock
    # The dataset's action is what the keys commanded: the twist integrates to 6 steps in -y.
    assert actions[:, 1].sum() / FPS == pytest.approx(-6 * STEP_M)
    assert np.all(actions[:, [0, 2, 3, 4, 5]] == 0.0) and np.all(actions[:, 6] == 0.0)
    # ...and the arm went that way (the recorded measured joints, through the same FK).
    states = np.stack(frames["observation.state"].to_numpy())
    fk = build_arm_kinematics(UR5E).fk
    moved = fk(states[-1, :-1])[:3] - fk(states[0, :-1])[:3]
    assert moved == pytest.approx([0.0, -6 * STEP_M, 0.0], abs=0.015)
