"""The keyboard as a Cartesian input device, with RMB's bindings plus arm and base keys.

RMB's ``KeyboardInputDevice`` (all deltas in the world frame, per control step):

====================  ====================================================
W / S                 +x / -x by 1 cm
A / D                 +y / -y by 1 cm
Q / E                 +z / -z by 1 cm
J / L                 roll -0.05 / +0.05 rad
I / K                 pitch +0.05 / -0.05 rad
U / O                 yaw +0.1 / -0.1 rad
Z / X                 gripper +50 / -50 (towards closed / open, 0..255)
====================  ====================================================

What RMB's lacks (its issue #26: its keyboard cannot drive a dual UR5e, ALOHA, HSR or G1):

- **Arm switch** (``num_arms > 1``): Tab selects the next arm, ``1`` .. ``9`` an arm by number;
  the motion keys move the selected arm only.
- **Mobile base** (``has_base``): arrow up / down drive forward / back, arrow left / right
  sideways (left = +y, as A), ``[`` / ``]`` turn left / right, at :attr:`KeyboardDevice.base_speed`
  and :attr:`KeyboardDevice.base_turn_speed` for the step of each press.

The device reads no keyboard itself: the teleop loop polls one
:class:`~rmb_lerobot.envs.teleop.device.KeySource` per step, keeps the phase keys and
:meth:`KeyboardDevice.feed` s the rest here, so a single terminal reader serves both.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np

from rmb_lerobot.envs.teleop.device import CartesianDelta, DeviceReading, InputDevice

POS_SCALE = 1e-2  # m per press (RMB's pos_scale)
RPY_SCALE = 5e-2  # rad per press (RMB's rpy_scale; yaw takes twice this)
GRIPPER_SCALE = 50.0  # command units per press on a 0..255 gripper (RMB's gripper_scale)
GRIPPER_RANGE_RMB = 255.0  # the range GRIPPER_SCALE is meant for

# key -> (position (3,), roll/pitch/yaw (3,), gripper) in units of the scales above.
MOTION_KEYS: dict[str, tuple[tuple[float, float, float], tuple[float, float, float], float]] = {
    "w": ((1, 0, 0), (0, 0, 0), 0),
    "s": ((-1, 0, 0), (0, 0, 0), 0),
    "a": ((0, 1, 0), (0, 0, 0), 0),
    "d": ((0, -1, 0), (0, 0, 0), 0),
    "q": ((0, 0, 1), (0, 0, 0), 0),
    "e": ((0, 0, -1), (0, 0, 0), 0),
    "j": ((0, 0, 0), (-1, 0, 0), 0),
    "l": ((0, 0, 0), (1, 0, 0), 0),
    "i": ((0, 0, 0), (0, 1, 0), 0),
    "k": ((0, 0, 0), (0, -1, 0), 0),
    "u": ((0, 0, 0), (0, 0, 2), 0),
    "o": ((0, 0, 0), (0, 0, -2), 0),
    "z": ((0, 0, 0), (0, 0, 0), 1),
    "x": ((0, 0, 0), (0, 0, 0), -1),
}
"""RMB's bindings: key -> unit deltas (yaw keys are 2 x ``rpy_scale``, as RMB's)."""

ARM_SWITCH_KEY = "tab"
# key -> (vx, vy, wz) in units of base_speed / base_turn_speed.
BASE_KEYS: dict[str, tuple[float, float, float]] = {
    "up": (1, 0, 0),
    "down": (-1, 0, 0),
    "left": (0, 1, 0),
    "right": (0, -1, 0),
    "[": (0, 0, 1),
    "]": (0, 0, -1),
}


class KeyboardDevice(InputDevice):
    """RMB's keyboard bindings as pose deltas, for one arm at a time, plus a mobile base.

    Args:
        num_arms: Arms of the robot (the arm switch keys select among them).
        has_base: Whether the robot has a mobile base (base keys are ignored otherwise).
        pos_scale: Metres per press.
        rpy_scale: Radians per roll / pitch press (yaw: twice this).
        gripper_step: Per arm, command units per Z / X press; one number for every arm.
            Default RMB's 50 (for a 0..255 gripper; see :func:`gripper_step_for`).
        base_speed: Base velocity (m/s) a base key commands for its step.
        base_turn_speed: Base turn rate (rad/s) of ``[`` / ``]``.

    Raises:
        ValueError: ``num_arms`` < 1 or a ``gripper_step`` per arm of the wrong length.
    """

    name = "keyboard"

    def __init__(
        self,
        num_arms: int = 1,
        has_base: bool = False,
        *,
        pos_scale: float = POS_SCALE,
        rpy_scale: float = RPY_SCALE,
        gripper_step: float | Sequence[float] = GRIPPER_SCALE,
        base_speed: float = 0.1,
        base_turn_speed: float = 0.3,
    ):
        if num_arms < 1:
            raise ValueError(f"num_arms must be >= 1, got {num_arms}")
        steps = [gripper_step] * num_arms if np.isscalar(gripper_step) else list(gripper_step)
        if len(steps) != num_arms:
            raise ValueError(f"gripper_step needs one value per arm ({num_arms}), got {steps}")
        self.num_arms = num_arms
        self.has_base = has_base
        self.pos_scale = pos_scale
        self.rpy_scale = rpy_scale
        self.gripper_steps = [float(s) for s in steps]
        self.base_speed = base_speed
        self.base_turn_speed = base_turn_speed
        self.arm = 0  # the arm the motion keys move
        self._keys: list[str] = []

    @property
    def keys(self) -> frozenset[str]:
        """Every key this device acts on (the loop feeds it these)."""
        keys = set(MOTION_KEYS)
        if self.num_arms > 1:
            keys |= {ARM_SWITCH_KEY, *(str(i + 1) for i in range(min(self.num_arms, 9)))}
        if self.has_base:
            keys |= set(BASE_KEYS)
        return frozenset(keys)

    def connect(self) -> None:
        """Nothing to open: keys arrive through :meth:`feed`."""
        self._keys.clear()

    def feed(self, keys: Iterable[str]) -> None:
        """Queue key presses for the next :meth:`read` (keys it does not use are dropped)."""
        self._keys.extend(key for key in keys if key in self.keys)

    def read(self) -> DeviceReading:
        """The queued presses as one step's deltas: the selected arm's pose and gripper, and
        the base velocity; an arm switch applies to the keys after it."""
        deltas: dict[int, list[np.ndarray]] = {}
        base = np.zeros(3)
        for key in self._keys:
            if key == ARM_SWITCH_KEY:
                self.arm = (self.arm + 1) % self.num_arms
            elif key.isdigit():
                self.arm = int(key) - 1
            elif key in BASE_KEYS:
                base += BASE_KEYS[key]
            else:
                pos, rpy, grip = MOTION_KEYS[key]
                total = deltas.setdefault(self.arm, [np.zeros(3), np.zeros(3), np.zeros(1)])
                total[0] += pos
                total[1] += rpy
                total[2] += grip
        self._keys.clear()
        arms = {
            arm: CartesianDelta(
                dpos=pos * self.pos_scale,
                drpy=rpy * self.rpy_scale,
                dgripper=float(grip[0]) * self.gripper_steps[arm],
            )
            for arm, (pos, rpy, grip) in deltas.items()
        }
        velocity = base * (self.base_speed, self.base_speed, self.base_turn_speed)
        return DeviceReading(arms=arms, base=velocity if self.has_base else None)

    def close(self) -> None:
        """Nothing to release."""
        self._keys.clear()


def gripper_step_for(command_range: tuple[float, float]) -> float:
    """RMB's gripper step scaled to a gripper's command range (50 for 0..255, 0.196 for 0..1).

    Args:
        command_range: ``(low, high)`` of the gripper command.

    Returns:
        Command units per Z / X press.
    """
    low, high = command_range
    return GRIPPER_SCALE * (high - low) / GRIPPER_RANGE_RMB
