"""The one small interface every arm driver (an SDK or its simulated twin) implements.

A driver speaks to one arm with its gripper and nothing else: no limits, no clamping, no
retries. What may be sent is decided by :mod:`rmb_lerobot.envs.real.safety`, which is the only
caller of :meth:`ArmDriver.command_joints` and :meth:`ArmDriver.command_gripper`.

Units are RMB's: joint positions in rad, velocities in rad/s, the gripper in the units of its
command (0..255 for a Robotiq 2F-85 and for RMB's xArm gripper command), wrench as
``(fx, fy, fz, tx, ty, tz)`` in N and N m.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np


class DriverError(RuntimeError):
    """The arm or its SDK failed; the message names the arm, the call and the reason."""


class ConnectionLost(DriverError):
    """The connection to the arm (or its gripper) dropped or never came up."""


class StaleState(ConnectionLost):
    """The arm's state stopped updating: its timestamp did not advance for longer than the
    driver allows, or the controller stopped answering requests (a stalled data link is a
    lost connection, so this is a :class:`ConnectionLost`)."""


class SdkError(DriverError):
    """An SDK call returned an error code (kept in :attr:`code`)."""

    def __init__(self, message: str, code: int):
        super().__init__(message)
        self.code = code


class ProtectiveStop(DriverError):
    """The controller stopped the arm (a joint limit, a collision, its own safety system)."""


class GripperFault(DriverError):
    """The gripper reported a fault or did not activate."""


@dataclass(frozen=True)
class ArmState:
    """One reading of the arm.

    Attributes:
        timestamp: The controller's clock (s) when the reading was taken; it must advance
            from one reading to the next (a reading that does not is stale).
        joint_pos: Arm joint positions (rad), in the record's joint order.
        joint_vel: Arm joint velocities (rad/s).
        gripper: The measured gripper value, in the units of its command.
        wrench: Force/torque at the wrist (6,), or ``None`` where the arm has no sensor.
    """

    timestamp: float
    joint_pos: np.ndarray
    joint_vel: np.ndarray
    gripper: float
    wrench: np.ndarray | None = None


@runtime_checkable
class ArmDriver(Protocol):
    """One arm with its gripper, as an SDK (or its twin) drives it.

    Every method raises a :class:`DriverError` subclass on failure, never returns a status.
    """

    def connect(self) -> None:
        """Open the connection, enable the arm and its gripper (activating it if needed)."""
        ...

    def read(self) -> ArmState:
        """The arm's current state."""
        ...

    def command_joints(self, joint_pos: np.ndarray, duration: float) -> None:
        """Move the arm joints to ``joint_pos`` (rad) over ``duration`` seconds, returning
        when the command is sent (the caller paces the loop)."""
        ...

    def command_gripper(self, value: float) -> None:
        """Move the gripper to ``value`` (units of its command), without waiting."""
        ...

    def zero_wrench(self) -> None:
        """Zero the force/torque sensor (RMB does it after every reset)."""
        ...

    def stop(self) -> None:
        """Stop the arm now (decelerate to rest); safe to call at any time, also twice."""
        ...

    def close(self) -> None:
        """Stop and disconnect; safe to call at any time, also twice."""
        ...
