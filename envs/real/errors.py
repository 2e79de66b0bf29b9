"""The refusals of the safety layer: one exception type per rule, all :class:`SafetyError`.

Every message names the robot, the joint (or field), the value and the limit it broke. When a
refusal is raised from a command or a state read, the layer has already called
``driver.stop()`` (see :mod:`rmb_lerobot.envs.real.safety`).
"""

from __future__ import annotations

from rmb_lerobot.envs.real import driver


class SafetyError(RuntimeError):
    """The safety layer refused a command or a reading; nothing was sent for it."""


class InvalidCommand(SafetyError):
    """The command has the wrong shape, or its duration is not in ``(0, max_duration]``."""


class NonFiniteCommand(SafetyError):
    """A joint target, the gripper value, the duration or the scale is NaN or infinite."""


class JumpTooLarge(SafetyError):
    """A joint is asked to move more than the jump threshold (RMB: 90°) in under the minimum
    duration (RMB: 0.1 s), or a reset would exceed the velocity limit."""


class OutsideWorkspace(SafetyError):
    """The TCP would leave the workspace box (or move further out of it)."""


class StaleReading(SafetyError, driver.StaleState):
    """The safety layer saw the controller's timestamp stop advancing (or go backwards).

    A subclass of the driver's :class:`~rmb_lerobot.envs.real.driver.StaleState` (a driver's
    own, looser stale check raises that one), so one ``except StaleState`` catches a stale arm
    from either, and ``except SafetyError`` catches every refusal of the layer.
    """


class InvalidState(SafetyError):
    """A reading has a NaN or infinite value, or the wrong shape."""


class WatchdogTripped(SafetyError):
    """Commands stopped arriving, the arm was stopped; call ``resume()`` before commanding."""


class LayerClosed(SafetyError):
    """The safety layer (and its driver) is closed."""
