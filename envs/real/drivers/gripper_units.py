"""The one place gripper command units are converted to a gripper SDK's units.

Drivers speak the gripper in the units of RMB's gripper command as the robot record gives it
(:class:`~rmb_lerobot.envs.robots.Gripper`): for the xArm7
(:data:`~rmb_lerobot.envs.robots.XARM7`) 0 = open .. 255 = closed, the command the simulated
xArm7 takes. The xArm gripper's SDK (``set_gripper_position`` / ``get_gripper_position``)
takes a pulse count, 840 = open .. 0 = closed (RMB's real xArm7 commands 0..840 and opens to
800; the gripper itself reaches about 850). The map is linear: ``pulse = 840 * (1 - c / 255)``
for the record's open (0) and closed (255) commands, and its inverse for readings. The Robotiq
2F-85 needs no map: its URCap position 0 (open) .. 255 (closed) is the command's unit.
"""

from __future__ import annotations

from rmb_lerobot.envs.robots import XARM7

XARM_GRIPPER_OPEN_PULSE = 840.0
"""The xArm gripper's pulse count RMB uses as fully open (its action's upper bound)."""
XARM_GRIPPER_CLOSED_PULSE = 0.0
"""The xArm gripper's pulse count when fully closed."""

_COMMAND_OPEN = XARM7.arms[0].gripper.open
_COMMAND_CLOSED = XARM7.arms[0].gripper.closed


def xarm_gripper_command_to_pulse(command: float) -> float:
    """An xArm7 gripper command (record units, 0 open .. 255 closed) as an SDK pulse count.

    Args:
        command: The gripper command.

    Returns:
        The pulse count (840 open .. 0 closed); not clipped (the safety layer bounds
        commands, and a reading outside the range says so).
    """
    s = (command - _COMMAND_OPEN) / (_COMMAND_CLOSED - _COMMAND_OPEN)
    return XARM_GRIPPER_OPEN_PULSE + s * (XARM_GRIPPER_CLOSED_PULSE - XARM_GRIPPER_OPEN_PULSE)


def xarm_gripper_pulse_to_command(pulse: float) -> float:
    """An xArm gripper pulse count (SDK units) in the record's command units.

    Args:
        pulse: The pulse count (840 open .. 0 closed).

    Returns:
        The gripper value, 0 open .. 255 closed (not clipped).
    """
    s = (pulse - XARM_GRIPPER_OPEN_PULSE) / (XARM_GRIPPER_CLOSED_PULSE - XARM_GRIPPER_OPEN_PULSE)
    return _COMMAND_OPEN + s * (_COMMAND_CLOSED - _COMMAND_OPEN)
