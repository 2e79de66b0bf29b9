"""``rmb-teleop`` with a SpaceMouse and a GELLO on a sim env, end to end (in-process ``main``).

The devices are the real device classes talking to their test doubles: a fake ``pyspacemouse``
module (scripted HID states) and a fake Dynamixel servo chain on a pty that the unmodified
``dynamixel-sdk`` talks to. Only the key source is scripted (the CLI would take the terminal):
``n`` -> standby, ``n`` -> teleop (recording), ``n`` -> end, ``s`` -> save, then Esc.
"""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest

from rmb_lerobot import keys as K
from rmb_lerobot.cli import teleop as cli
from rmb_lerobot.envs.registry import entry_for
from rmb_lerobot.envs.teleop.command import CommandTracker
from rmb_lerobot.envs.teleop.fakes.spacemouse import FakePySpaceMouse, FakeState
from rmb_lerobot.envs.teleop.keys import ScriptedKeySource
from rmb_lerobot.episode import find_episodes, open_episode

SMALL = ["--cameras", "front", "--image-size", "48", "32", "--no-depth", "--no-realtime"]
READS_PER_STEP = 10  # the SpaceMouse device reads 10 queued HID reports per control step


def keys(*events: tuple[int, str]) -> ScriptedKeySource:
    return ScriptedKeySource(events)


def run_cli(monkeypatch, tmp_path, key_source, argv: list[str]) -> list:
    monkeypatch.setattr(cli, "make_key_source", lambda kind: key_source)
    out = tmp_path / "out"
    assert cli.main([*argv, "--out", str(out), *SMALL]) == 0
    return find_episodes(out)


def home_joints(env_name: str) -> np.ndarray:
    """The robot's measured joints after a reset (every world starts the arm at home)."""
    env = entry_for(env_name).make(cameras=())
    try:
        env.reset(seed=0)
        return env.measured_joint_pos()
    finally:
        env.close()


def in_root_frames(env_name: str, world_moves: list[np.ndarray]) -> list[np.ndarray]:
    """World-frame displacements (one per arm) in each arm's root frame, where RMB records
    eef poses (the UR5e's base is turned by pi: world +y is its root's -y)."""
    env = entry_for(env_name).make(cameras=())
    try:
        env.reset(seed=0)
        rotations = CommandTracker(env).root_from_world
        return [rot @ move for rot, move in zip(rotations, world_moves, strict=True)]
    finally:
        env.close()


# ---------------------------------------------------------------------------- SpaceMouse
PUSH_STEPS, HOLD_STEPS = 20, 25
# HID +x (pushed right) is RMB's legacy +x: dpos = 1e-2 * (-y, x, z) = +y world, 5 mm a step.
PUSH = FakeState(x=0.5)


def pushed_then_released(push: FakeState) -> list[FakeState]:
    return [push] * (READS_PER_STEP * PUSH_STEPS) + [FakeState()]


def spacemouse_keys() -> ScriptedKeySource:
    end = 1 + PUSH_STEPS + HOLD_STEPS
    return keys((0, "n"), (1, "n"), (end, "n"), (end + 1, "s"))


def test_a_spacemouse_moves_the_recorded_end_effector_by_rmbs_scale(monkeypatch, tmp_path):
    fake = FakePySpaceMouse({"/dev/hidraw0": pushed_then_released(PUSH)})
    monkeypatch.setitem(sys.modules, "pyspacemouse", fake)
    [path] = run_cli(
        monkeypatch, tmp_path, spacemouse_keys(), ["cable", "--input-device", "spacemouse"]
    )
    assert path.name.startswith("MujocoUR5eCable_world") and path.name.endswith("_000.rmb")
    assert [d.closed for d in fake.opened] == [True]  # closed when the CLI quit
    with open_episode(path) as ep:
        assert len(ep) == PUSH_STEPS + HOLD_STEPS
        command, measured = ep[K.COMMAND_EEF_POSE][:], ep[K.MEASURED_EEF_POSE][:]
    # Row k pairs the state before step k with the command sent at k: the first row's command
    # already holds one push; the target then moved 5 mm a step towards world +y, no more.
    [expected] = in_root_frames("cable", [np.array([0.0, 0.005 * (PUSH_STEPS - 1), 0.0])])
    # (command_eef_pose is the forward kinematics of the IK's joints: its residual, < 0.05 mm.)
    np.testing.assert_allclose(command[-1, :3] - command[0, :3], expected, atol=5e-5)
    np.testing.assert_allclose(command[-1, 3:], command[0, 3:], atol=5e-4)  # no rotation
    # The arm followed the target (IK + position servos) within a few millimetres.
    [expected] = in_root_frames("cable", [np.array([0.0, 0.005 * PUSH_STEPS, 0.0])])
    np.testing.assert_allclose(measured[-1, :3] - measured[0, :3], expected, atol=0.006)


def test_two_spacemice_drive_the_two_arms_of_the_dual_ur5e(monkeypatch, tmp_path):
    # Arm 0's mouse pushed up (HID -z is legacy +z: +z world), arm 1's pushed right (+y).
    fake = FakePySpaceMouse(
        {
            "/dev/hidraw3": pushed_then_released(FakeState(z=-0.5)),
            "/dev/hidraw4": pushed_then_released(PUSH),
        }
    )
    monkeypatch.setitem(sys.modules, "pyspacemouse", fake)
    config = tmp_path / "SpaceMouseDual.yaml"
    config.write_text(
        "0:\n  device_params:\n    path: /dev/hidraw3\n"
        "1:\n  device_params:\n    path: /dev/hidraw4\n"
    )
    argv = ["MujocoUR5eDualCable", "--input-device", "spacemouse"]
    argv += ["--input-device-config", str(config)]
    [path] = run_cli(monkeypatch, tmp_path, spacemouse_keys(), argv)
    assert [d.path for d in fake.opened] == ["/dev/hidraw3", "/dev/hidraw4"]
    with open_episode(path) as ep:
        command = ep[K.COMMAND_EEF_POSE][:].reshape(-1, 2, 7)
        measured = ep[K.MEASURED_EEF_POSE][:].reshape(-1, 2, 7)
    up, right = np.array([0.0, 0.0, 0.005]), np.array([0.0, 0.005, 0.0])
    name = "MujocoUR5eDualCable"
    targets = in_root_frames(name, [up * (PUSH_STEPS - 1), right * (PUSH_STEPS - 1)])
    reached = in_root_frames(name, [up * PUSH_STEPS, right * PUSH_STEPS])
    for arm in (0, 1):
        moved = command[-1, arm, :3] - command[0, arm, :3]
        np.testing.assert_allclose(moved, targets[arm], atol=5e-5, err_msg=f"arm {arm}")
        followed = measured[-1, arm, :3] - measured[0, arm, :3]
        # Lifting lags most (gravity against the position servos): within 1 cm of 10 cm.
        np.testing.assert_allclose(followed, reached[arm], atol=0.01, err_msg=f"arm {arm}")


# ---------------------------------------------------------------------------- GELLO
pytest.importorskip("dynamixel_sdk", reason="extra gello (in `make setup`'s EXTRAS)")

from rmb_lerobot.envs.teleop.fakes.dynamixel import FakeDynamixelChain  # noqa: E402

# A UR5e GELLO calibrated like RMB's (offsets multiples of π/2, one sign -1), gripper servo 7
# reading 202.04 deg open and 160.24 deg closed.
OFFSETS = (math.pi, 1.5 * math.pi, math.pi, -0.5 * math.pi, math.pi, 2 * math.pi)
SIGNS = (1, 1, -1, 1, 1, 1)
GRIPPER = (7, 202.04, 160.24)


def servo_counts(q: np.ndarray, gripper_deg: float = GRIPPER[1]) -> dict[int, int]:
    """Raw servo positions that make the GELLO read arm joints ``q`` and the gripper angle."""
    rad = np.asarray(q) * np.asarray(SIGNS) + np.asarray(OFFSETS)
    counts = {i + 1: round(r / math.pi * 2048) for i, r in enumerate(rad)}
    counts[GRIPPER[0]] = round(math.radians(gripper_deg) / math.pi * 2048)
    return counts


def gello_yaml(tmp_path, port: str):
    path = tmp_path / "Gello_UR5e.yaml"
    path.write_text(
        f"0:\n  port: {port}\n  config:\n    joint_ids: [1, 2, 3, 4, 5, 6]\n"
        f"    joint_signs: {list(SIGNS)}\n    joint_offsets: {list(OFFSETS)}\n"
        f"    gripper_config: {list(GRIPPER)}\n"
    )
    return path


class HandOnTheLeader(ScriptedKeySource):
    """Scripted keys, and at poll ``move_at`` the operator moves the leader arm to ``counts``."""

    def __init__(self, events, chain: FakeDynamixelChain, move_at: int, counts: dict[int, int]):
        super().__init__(events)
        self.chain, self.move_at, self.counts = chain, move_at, counts

    def poll(self) -> list[str]:
        if self.polls == self.move_at:
            self.chain.set_positions(self.counts)
        return super().poll()


def test_gello_waits_until_ready_blends_in_and_the_arm_follows_the_servos(
    monkeypatch, tmp_path, capsys
):
    home = home_joints("cable")[:6]
    far = home + np.radians([40, 0, 0, 0, 0, 0])  # beyond the 30 deg readiness tolerance
    near = home + np.radians([15, -10, 8, 0, 10, -15])
    recorded = 70
    with FakeDynamixelChain(servo_counts(far)) as chain:
        # n (standby), n at 2 refused (not ready), the leader moved at 4, n at 5: teleop;
        # recording until n, then save.
        source = HandOnTheLeader(
            [(0, "n"), (2, "n"), (5, "n"), (5 + recorded, "n"), (6 + recorded, "s")],
            chain,
            move_at=4,
            counts=servo_counts(near, gripper_deg=181.14),  # gripper half closed
        )
        argv = ["cable", "--input-device", "gello"]
        argv += ["--input-device-config", str(gello_yaml(tmp_path, chain.path))]
        [path] = run_cli(monkeypatch, tmp_path, source, argv)
    assert "arm 0 joint 0: 40 deg" in capsys.readouterr().err  # why 'n' was refused
    with open_episode(path) as ep:
        assert len(ep) == recorded
        command, measured = ep[K.COMMAND_JOINT_POS][:], ep[K.MEASURED_JOINT_POS][:]
    device = np.array([v / 2048 * math.pi for v in list(servo_counts(near).values())[:6]])
    device = (device - np.asarray(OFFSETS)) * np.asarray(SIGNS)  # what the servos read
    # The blend starts at the robot's measured joints and never overshoots the device pose ...
    np.testing.assert_allclose(command[0, :6], measured[0, :6], atol=1e-3)
    gaps = np.abs(command[:, :6] - device).max(axis=1)
    assert np.all(np.diff(gaps[:50]) <= 1e-9)
    # ... which the command reaches after 50 steps (gello's smoothing has converged) ...
    np.testing.assert_allclose(command[55:, :6], np.tile(device, (recorded - 55, 1)), atol=1e-6)
    # ... and the simulated arm follows the servos.
    np.testing.assert_allclose(measured[-1, :6], device, atol=0.02)
    gripper = entry_for("cable").robot_record.arms[0].gripper
    assert command[-1, 6] == pytest.approx(
        gripper.open + 0.5 * (gripper.closed - gripper.open), rel=0.01
    )
