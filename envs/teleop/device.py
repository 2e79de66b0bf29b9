"""The one interface every teleoperation input device implements (RMB's ``InputDeviceBase``).

A device turns what a person does into commands for one or more arms (and a mobile base):
Cartesian devices (keyboard, SpaceMouse) give a pose *delta* per step that the teleop loop adds
to its end-effector target and solves by IK; joint-space devices (GELLO) give joint targets.
Phase keys (next / save / discard / quit) are not part of a device: they come from a
:class:`KeySource`, as RMB takes them from its window rather than from the device.

Devices are used as context managers or with explicit :meth:`InputDevice.connect` /
:meth:`InputDevice.close`; SDKs are imported in ``connect`` (lazily), never at import time.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np


@dataclass(frozen=True)
class CartesianDelta:
    """One step of a Cartesian device for one arm, in the world frame.

    Attributes:
        dpos: Position change (3,) in metres.
        drpy: Rotation change (3,) roll, pitch, yaw in radians, applied in the world frame
            (``R(drpy) @ R_target``, RMB's rule).
        dgripper: Gripper command change in the arm's own command units (0..255 for the
            Robotiq and xArm grippers); positive moves towards closed.
    """

    dpos: np.ndarray
    drpy: np.ndarray
    dgripper: float = 0.0


@dataclass(frozen=True)
class JointTarget:
    """One step of a joint-space device (GELLO) for one arm.

    Attributes:
        joints: Arm joint targets (n,) in radians, in the robot's joint order.
        gripper: Gripper closure in [0, 1] (0 open, 1 closed); the loop maps it onto the arm's
            command range.
    """

    joints: np.ndarray
    gripper: float


ArmCommand = CartesianDelta | JointTarget


@dataclass(frozen=True)
class DeviceReading:
    """What a device reports in one control step.

    Attributes:
        arms: Command per arm index (0 = first arm of the robot record); an arm the device does
            not move this step is absent.
        base: Mobile-base velocity (3,) ``(vx, vy, wz)`` in the base's local frame (m/s, rad/s),
            or None when the device does not drive a base.
    """

    arms: Mapping[int, ArmCommand] = field(default_factory=dict)
    base: np.ndarray | None = None


class InputDevice(ABC):
    """A teleoperation input device: connect, read once per control step, close.

    Subclasses set :attr:`name` and implement :meth:`connect`, :meth:`read` and :meth:`close`;
    :meth:`is_ready` defaults to True (a joint-space device overrides it so that the robot is
    not yanked towards a device pose far from its own).
    """

    name: str = "device"

    @abstractmethod
    def connect(self) -> None:
        """Open the device (import its SDK here, not at module import).

        Raises:
            ImportError: The device's optional extra is not installed (the message names it).
            ConnectionError: The device is absent or does not answer.
        """

    @abstractmethod
    def read(self) -> DeviceReading:
        """Return this step's commands; never blocks longer than one control period."""

    def is_ready(self, measured_joints: Sequence[np.ndarray]) -> bool:
        """Whether the device may start driving the robot.

        Args:
            measured_joints: Each arm's measured joint positions (rad), in record order.

        Returns:
            True when recording may start from the robot's current state.
        """
        del measured_joints
        return True

    @abstractmethod
    def close(self) -> None:
        """Release the device; safe to call twice."""

    def __enter__(self) -> InputDevice:
        self.connect()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class KeySource(Protocol):
    """Where discrete key presses come from (a terminal, a window, a scripted test).

    Keys are lower-case characters (``"n"``, ``"s"``, ``"f"``, ``"w"``) or names (``"esc"``,
    ``"space"``, ``"up"``); each press is reported once.
    """

    def poll(self) -> list[str]:
        """Return the keys pressed since the last call (possibly none), oldest first."""
        ...

    def close(self) -> None:
        """Stop listening and restore the terminal or window; safe to call twice."""
        ...
