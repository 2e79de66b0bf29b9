"""Test doubles for code above the driver: a recording fake arm and a manual clock.

:class:`FakeArm` implements :class:`~rmb_lerobot.envs.real.driver.ArmDriver` with no physics: a
joint command moves the arm (all the way, or a fraction with ``track``) at once, every call is
recorded, and faults can be planted (a timestamp that stops advancing or goes backwards, a NaN
reading, a driver error). For anything that needs timing, contact or an SDK's calls, use the
MuJoCo-backed twins instead.
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rmb_lerobot.envs.real.driver import ArmState


def wait_for(done: Callable[[], bool], timeout_s: float = 15.0, poll_s: float = 0.02) -> bool:
    """Poll ``done`` until it is true or ``timeout_s`` passes (twins run in wall-clock time).

    Args:
        done: The condition.
        timeout_s: Bound (s); generous by default, for loaded machines.
        poll_s: Polling period (s).

    Returns:
        Whether ``done`` became true (checked once more at the deadline).
    """
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if done():
            return True
        time.sleep(poll_s)
    return bool(done())


class FakeClock:
    """A clock that moves only when told to (inject it as ``clock=``).

    Args:
        start: The initial time (s).
    """

    def __init__(self, start: float = 0.0):
        self.now = float(start)

    def __call__(self) -> float:
        return self.now

    def advance(self, seconds: float) -> None:
        """Move the clock forward.

        Args:
            seconds: How far (s).
        """
        self.now += float(seconds)


@dataclass(frozen=True)
class JointCommand:
    """One ``command_joints`` call as the fake arm received it.

    Attributes:
        joint_pos: The targets (a copy).
        duration: The duration (s).
        measured: The last reading the arm handed out before the call.
        stale_reads: How many readings in a row, up to that one, had a timestamp that did not
            advance (0: it advanced).
    """

    joint_pos: np.ndarray
    duration: float
    measured: ArmState | None
    stale_reads: int


class FakeArm:
    """A recording :class:`ArmDriver` with no physics.

    Args:
        joint_pos: The initial arm joint positions (rad).
        gripper: The initial gripper value.
        timestamp_step: How far the controller timestamp advances per read (s).
        track: The fraction of the way to a joint target the arm moves per command.

    Attributes:
        commands: Every ``command_joints`` call.
        gripper_commands: Every ``command_gripper`` value.
        calls: The names of all calls, in order.
        stops: How many times ``stop`` was called.
    """

    def __init__(
        self,
        joint_pos: np.ndarray,
        *,
        gripper: float = 0.0,
        timestamp_step: float = 0.002,
        track: float = 1.0,
    ):
        self.joint_pos = np.array(joint_pos, dtype=np.float64)
        self.gripper = float(gripper)
        self.timestamp = 0.0
        self.timestamp_step = float(timestamp_step)
        self.track = float(track)
        self.commands: list[JointCommand] = []
        self.gripper_commands: list[float] = []
        self.calls: list[str] = []
        self.stops = 0
        self.connected = False
        self.closed = False
        self.last_read: ArmState | None = None
        self.stale_reads = 0
        # Planted faults, consumed by the next reads / commands.
        self.hold_timestamp = 0  # this many reads do not advance the timestamp
        self.rewind = 0.0  # the next reading's timestamp is this much earlier than the last
        self.nan_joint: int | None = None  # the next read has NaN at this joint
        self.fail_next_command: BaseException | None = None

    def connect(self) -> None:
        """Connect (records the call)."""
        self.calls.append("connect")
        self.connected = True

    def read(self) -> ArmState:
        """A reading, with any planted fault applied.

        Returns:
            The arm's state.
        """
        self.calls.append("read")
        timestamp = self.timestamp
        if self.rewind:
            timestamp -= self.rewind  # this reading only; the clock itself goes on
            self.rewind = 0.0
            self.stale_reads += 1
        elif self.hold_timestamp > 0:
            self.hold_timestamp -= 1
            self.stale_reads += 1
        else:
            self.timestamp += self.timestamp_step
            timestamp = self.timestamp
            self.stale_reads = 0
        joint_pos = self.joint_pos.copy()
        if self.nan_joint is not None:
            joint_pos[self.nan_joint] = np.nan
            self.nan_joint = None
        self.last_read = ArmState(
            timestamp=timestamp,
            joint_pos=joint_pos,
            joint_vel=np.zeros_like(joint_pos),
            gripper=self.gripper,
            wrench=np.zeros(6),
        )
        return self.last_read

    def command_joints(self, joint_pos: np.ndarray, duration: float) -> None:
        """Record the command and move (a ``track`` fraction of) the way there.

        Args:
            joint_pos: Joint targets (rad).
            duration: Duration (s).

        Raises:
            BaseException: A planted failure (``fail_next_command``).
        """
        self.calls.append("command_joints")
        if self.fail_next_command is not None:
            exc, self.fail_next_command = self.fail_next_command, None
            raise exc
        target = np.array(joint_pos, dtype=np.float64)
        self.commands.append(
            JointCommand(target, float(duration), self.last_read, self.stale_reads)
        )
        self.joint_pos = self.joint_pos + self.track * (target - self.joint_pos)

    def command_gripper(self, value: float) -> None:
        """Record the gripper command and take it at once.

        Args:
            value: Gripper command.
        """
        self.calls.append("command_gripper")
        self.gripper_commands.append(float(value))
        self.gripper = float(value)

    def zero_wrench(self) -> None:
        """Record the call."""
        self.calls.append("zero_wrench")

    def stop(self) -> None:
        """Record the stop."""
        self.calls.append("stop")
        self.stops += 1

    def close(self) -> None:
        """Record the close."""
        self.calls.append("close")
        self.closed = True


def lerobot_cli_env(home: Path, **extra: str) -> dict[str, str]:
    """The environment for running LeRobot's CLIs against the twins: offline, LeRobot's home
    and calibration directory under ``home``, no wandb.

    Args:
        home: A scratch directory (a test's ``tmp_path``).
        **extra: More variables (e.g. ``PYTHONPATH``).

    Returns:
        A copy of this process's environment with those set.
    """
    return {
        **os.environ,
        "HF_HUB_OFFLINE": "1",
        "HF_LEROBOT_HOME": str(home / "hf_lerobot"),
        "HF_LEROBOT_CALIBRATION": str(home / "calibration"),
        "WANDB_MODE": "disabled",
        **extra,
    }


def lerobot_cli_command(script: str) -> list[str]:
    """``lerobot-<script>``: the console script beside this interpreter, else its module."""
    exe = Path(sys.executable).with_name(f"lerobot-{script}")
    if exe.exists():
        return [str(exe)]
    return [sys.executable, "-m", f"lerobot.scripts.lerobot_{script}"]
