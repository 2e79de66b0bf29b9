"""LeRobot's unmodified CLIs on the UR5e twin with ``rmb_gello`` and ``rmb_spacemouse``.

``lerobot-teleoperate`` with a GELLO: a fake servo chain on a pty served by this test process;
the CLI (another process) opens the pty's slave path with the real dynamixel-sdk, exactly as
it would open ``/dev/ttyUSB0``. The leader starts 40° away on the base joint, so the robot is
held; once the loop runs, the test moves the leader next to the robot's pose and the
teleoperator takes over.

``lerobot-record`` with a SpaceMouse: a ``pyspacemouse`` stand-in first on the CLI's
``PYTHONPATH`` plays a held push; the robot runs ``--robot.action_space=ee_velocity``; the
dataset stores the twist, the twin's end effector moves by it, and the recording converts to
RMB episodes. Offline, loopback only, HF_LEROBOT_HOME and the calibration directory in tmp.
"""

from __future__ import annotations

import json
import math
import os
import re
import subprocess
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

pytest.importorskip("dynamixel_sdk", reason="extra gello (in `make setup`'s EXTRAS)")

from rmb_lerobot.envs.real.lerobot_devices.features import action_keys, home_vector
from rmb_lerobot.envs.real.testing import lerobot_cli_command, lerobot_cli_env
from rmb_lerobot.envs.teleop.fakes.dynamixel import INST_SYNC_READ, FakeDynamixelChain
from rmb_lerobot.envs.teleop.fakes.spacemouse import FakeState, write_module

CLI_TIMEOUT_S = 600  # one CLI: ~25 s to start on an idle 2-core machine, minutes when loaded
TELEOP_TIME_S = 8
# The tests are about the teleoperators: a loop step stalled by a loaded machine must not trip
# the safety layer's watchdog (its own tests cover it).
WATCHDOG_S = 5.0
HOME = home_vector("rmb_ur5e")[:6]
OFFSETS = [math.pi, 1.5 * math.pi, math.pi, -0.5 * math.pi, math.pi, 2 * math.pi]
SIGNS = [1, 1, -1, 1, 1, 1]


def gello_raw(q: np.ndarray) -> dict[int, int]:
    rad = np.asarray(q) * SIGNS + OFFSETS
    return {i + 1: round(r / math.pi * 2048) for i, r in enumerate(rad)} | {7: 2299}


def wait_for(condition, timeout_s: float, process: subprocess.Popen) -> bool:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline and process.poll() is None:
        if condition():
            return True
        time.sleep(0.05)
    return condition()


def start_cli(script: str, args: list[str], tmp_path: Path, env: dict) -> subprocess.Popen:
    """Start ``lerobot-<script>`` (the console script beside this interpreter), logging to tmp."""
    with open(tmp_path / f"{script}.log", "w") as out:  # the child keeps its own descriptor
        return subprocess.Popen(
            [*lerobot_cli_command(script), *args],
            cwd=tmp_path,
            env=env,
            stdout=out,
            stderr=subprocess.STDOUT,
        )


def finish(process: subprocess.Popen, tmp_path: Path, script: str) -> str:
    try:
        process.wait(timeout=CLI_TIMEOUT_S)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    text = (tmp_path / f"{script}.log").read_text()
    assert process.returncode == 0, f"{script}: exit {process.returncode}\n{text[-4000:]}"
    assert "Traceback" not in text, text[-4000:]
    return text


@pytest.mark.timeout(900)  # a LeRobot CLI start on a loaded machine
def test_lerobot_teleoperate_drives_the_twin_with_a_gello_on_a_pty(tmp_path):
    with FakeDynamixelChain(gello_raw(HOME + np.radians([40, 0, 0, 0, 0, 0]))) as chain:
        args = [
            "--robot.type=rmb_ur5e",
            "--robot.driver=sim",
            f"--robot.watchdog_timeout_s={WATCHDOG_S}",
            "--teleop.type=rmb_gello",
            f"--teleop.port={chain.path}",
            f"--teleop.joint_offsets={OFFSETS}",
            f"--teleop.joint_signs={SIGNS}",
            "--teleop.gripper=[7, 202.04, 160.24]",
            f"--teleop_time_s={TELEOP_TIME_S}",
            "--fps=30",
        ]
        process = start_cli("teleoperate", args, tmp_path, lerobot_cli_env(tmp_path))
        log = tmp_path / "teleoperate.log"
        try:
            # Connect pings each servo and aligns (one sync read); then one read per step.
            running = wait_for(lambda: chain.received[INST_SYNC_READ] >= 5, CLI_TIMEOUT_S, process)
            assert running, f"the loop never read the GELLO:\n{log.read_text()[-4000:]}"
            held = chain.received[INST_SYNC_READ]
            chain.set_positions(gello_raw(HOME + np.radians([10, -5, 5, 0, 0, 10])))
            text = finish(process, tmp_path, "teleoperate")
        finally:
            if process.poll() is None:
                process.kill()
                process.wait()
    assert "GELLO is not ready" in text and "arm 0 joint 0: 40 deg" in text
    assert "GELLO ready: blending into its pose over 50 steps" in text
    assert "Teleop loop time" in text
    # The loop kept reading the leader after the handover (well under 30 Hz when loaded).
    assert chain.received[INST_SYNC_READ] - held >= 10


POS_SCALE = 1e-3  # m per step at full deflection: a slow, short push
PUSH = 0.5  # the cap pushed halfway to the right (HID +x): RMB's +y


@pytest.mark.timeout(1200)  # a LeRobot CLI start on a loaded machine, then a conversion
def test_lerobot_record_with_a_spacemouse_moves_the_twin_and_converts(tmp_path, capsys):
    shim = tmp_path / "shim"
    write_module(shim, {"/dev/hidraw0": [FakeState(x=PUSH)]})  # held for the whole episode
    dataset = tmp_path / "dataset"
    cameras = "{front: {type: rmb_twin, width: 32, height: 24, fps: 30, use_depth: false}}"
    args = [
        "--robot.type=rmb_ur5e",
        "--robot.driver=sim",
        f"--robot.watchdog_timeout_s={WATCHDOG_S}",
        "--robot.action_space=ee_velocity",
        f"--robot.cameras={cameras}",
        "--teleop.type=rmb_spacemouse",
        "--teleop.path=/dev/hidraw0",
        f"--teleop.pos_scale={POS_SCALE}",
        "--dataset.repo_id=local/rmb_spacemouse",
        f"--dataset.root={dataset}",
        "--dataset.num_episodes=1",
        "--dataset.episode_time_s=2",
        "--dataset.reset_time_s=0",
        "--dataset.fps=30",
        "--dataset.single_task=push right",
        "--dataset.push_to_hub=false",
        "--dataset.no_stamp=true",
        "--play_sounds=false",
    ]
    paths = [str(shim), *filter(None, [os.environ.get("PYTHONPATH")])]
    env = lerobot_cli_env(tmp_path, PYTHONPATH=os.pathsep.join(paths))
    text = finish(start_cli("record", args, tmp_path, env), tmp_path, "record")

    info = json.loads((dataset / "meta" / "info.json").read_text())
    names = info["features"]["action"]["names"]
    assert info["robot_type"] == "rmb_ur5e" and names == list(
        action_keys("rmb_ur5e", "ee_velocity")
    )
    frames = info["total_frames"]
    assert frames >= 10  # 2 s at 30 fps, frames dropped when loaded
    actions = np.concatenate(
        [
            np.stack(pd.read_parquet(f)["action"].to_numpy())
            for f in sorted(dataset.glob("data/**/*.parquet"))
        ]
    )
    # Every stored action is RMB's step over the command duration: +y only, gripper open.
    step = POS_SCALE * PUSH
    expected = np.array([0, step * 30, 0, 0, 0, 0, 0])
    np.testing.assert_allclose(actions, np.tile(expected, (len(actions), 1)), atol=1e-6)
    # The twin's end effector moved by one step per action sent, along +y.
    poses = {
        when: np.array(json.loads(m.group(1)))
        for when, m in (
            (w, re.search(rf"end effector {w} at (\[[^\]]*\]) m", text)) for w in ("starts", "ends")
        )
        if m
    }
    assert set(poses) == {"starts", "ends"}, text[-3000:]
    moved = poses["ends"] - poses["starts"]
    np.testing.assert_allclose(moved, [0, frames * step, 0], atol=0.002)

    from rmb_lerobot.cli.convert import main as convert
    from rmb_lerobot.cli.data import main as data

    episodes = tmp_path / "rmb"
    assert convert(["from-lerobot", "--root", str(dataset), "--output", str(episodes)]) == 0
    capsys.readouterr()
    assert data(["info", str(episodes)]) == 0
    described = capsys.readouterr().out
    assert "1 episode(s)" in described and "env: 'rmb_ur5e'" in described
