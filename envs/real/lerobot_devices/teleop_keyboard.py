"""``rmb_keyboard``: RMB's keyboard bindings as a LeRobot teleoperator that works headless.

LeRobot's own ``keyboard`` teleoperators listen through pynput only, so with no display they
never connect (``get_action`` raises). This one reads keys from a
:class:`~rmb_lerobot.envs.teleop.keys.TerminalKeySource` (the terminal on standard input in
cbreak mode: over SSH, in a container, on a pty in tests) or, where a display exists, a
:class:`~rmb_lerobot.envs.teleop.keys.PynputKeySource`, turns them into RMB's pose steps with
:class:`~rmb_lerobot.envs.teleop.keyboard.KeyboardDevice` and emits them as the end-effector
velocity action of a robot with ``action_space: ee_velocity`` (:mod:`.ee_action`): the robot,
not the teleoperator, holds the end-effector target, so the teleoperator needs no robot state.

Sharing the terminal with ``lerobot-record``. LeRobot's recording controls (→ / ``n`` next,
← / ``r`` re-record, Esc stop) read standard input too when it is a terminal, and two readers
of one terminal each get only some of the key presses. So when this teleoperator reads the
terminal on standard input it becomes its only reader: it moves standard input onto a fresh
pseudo-terminal (LeRobot's listener, started after the teleoperator connects, reads that one)
and forwards there the keys LeRobot uses and RMB's bindings do not (→, ←, Esc, ``n``, ``r``).
RMB's ``q`` (+z) is not forwarded, so it never stops a recording; Esc does. Standard input is
put back on :meth:`RmbKeyboard.disconnect`.
"""

from __future__ import annotations

import contextlib
import os
import pty
from typing import Any

from lerobot.utils.errors import DeviceAlreadyConnectedError, DeviceNotConnectedError

from rmb_lerobot.envs.real.lerobot_devices.config import EE_VELOCITY_ACTIONS, RmbKeyboardConfig
from rmb_lerobot.envs.real.lerobot_devices.features import (
    DUAL_SIDES,
    EE_VELOCITY_KEYS,
    GRIPPER_KEY,
    action_keys,
    single_arm_record,
)
from rmb_lerobot.envs.real.lerobot_devices.teleop_base import KeyedTeleoperator, RateCheck
from rmb_lerobot.envs.teleop.device import KeySource
from rmb_lerobot.envs.teleop.keyboard import KeyboardDevice, gripper_step_for

FORWARDED_KEYS = {"right": "\x1b[C", "left": "\x1b[D", "esc": "\x1b", "n": "n", "r": "r"}
"""Keys LeRobot's recording controls use and RMB's bindings do not -> the bytes forwarded."""


class StdinRouter:
    """Standard input moved onto a pseudo-terminal this process writes to.

    The real terminal stays readable through :attr:`terminal_fd` (a duplicate of the old
    standard input); every other reader of standard input in this process (LeRobot's
    recording controls) reads the pseudo-terminal, which gets only what :meth:`forward`
    writes.

    Raises:
        OSError: Standard input is not a terminal.
    """

    def __init__(self) -> None:
        if not os.isatty(0):
            raise OSError("standard input is not a terminal")
        self.terminal_fd = os.dup(0)
        self._master, self._slave = pty.openpty()
        os.dup2(self._slave, 0)

    def forward(self, keys: list[str]) -> None:
        """Write the keys LeRobot uses (:data:`FORWARDED_KEYS`) to the pseudo-terminal.

        Args:
            keys: Key names as the key source reports them.
        """
        data = "".join(FORWARDED_KEYS[key] for key in keys if key in FORWARDED_KEYS)
        if data and self._master >= 0:
            os.write(self._master, data.encode())

    def close(self) -> None:
        """Put the real terminal back on standard input; safe to call twice."""
        if self._master < 0:
            return
        os.dup2(self.terminal_fd, 0)
        for fd in (self._master, self._slave, self.terminal_fd):
            with contextlib.suppress(OSError):
                os.close(fd)
        self._master = self._slave = -1


def open_key_source(kind: str) -> tuple[KeySource, StdinRouter | None]:
    """The key source ``kind`` names, and the router when it reads standard input.

    Args:
        kind: ``auto``, ``terminal`` or ``pynput`` (see :class:`RmbKeyboardConfig`).

    Returns:
        The source and, for the terminal on standard input, the :class:`StdinRouter`.

    Raises:
        ConnectionError: No usable source: no terminal on standard input and no display
            (with pynput), named in the message.
        ImportError: ``pynput`` asked for without pynput installed.
    """
    from rmb_lerobot.display import has_display
    from rmb_lerobot.envs.teleop.keys import PynputKeySource, TerminalKeySource, stdin_is_terminal

    if kind == "terminal" or (kind == "auto" and stdin_is_terminal()):
        if stdin_is_terminal():
            router = StdinRouter()
            try:
                return TerminalKeySource(router.terminal_fd), router
            except BaseException:
                router.close()
                raise
        try:
            return TerminalKeySource(), None  # the controlling terminal (/dev/tty)
        except OSError as exc:
            raise ConnectionError(
                "rmb_keyboard: keys=terminal, but neither standard input nor /dev/tty is a "
                f"terminal ({exc}); run the command in a terminal (over SSH works)"
            ) from exc
    if kind == "pynput" or has_display():
        try:
            return PynputKeySource(), None
        except ImportError as exc:
            raise ImportError(
                f"rmb_keyboard: {exc}. Or read the terminal instead: run the command in one "
                "with --teleop.keys=terminal"
            ) from exc
    raise ConnectionError(
        "rmb_keyboard: no keyboard to read: standard input is not a terminal and there is no "
        "display (DISPLAY / WAYLAND_DISPLAY) for pynput; run the LeRobot command in a terminal "
        "(over SSH works) and it reads the keys there"
    )


class RmbKeyboard(KeyedTeleoperator):
    """RMB's keyboard bindings emitting end-effector velocity actions.

    Per step it polls the key source once and returns, per arm, the twist that moves the
    robot's end-effector target by the presses' steps in one loop period (``step * fps``;
    zero when no key was pressed) and the gripper command it tracks from
    ``gripper_start`` (Z closes, X opens by RMB's 50 of 255). A warning names ``--fps`` when
    the loop polls it at another period than ``1 / fps`` (:class:`~.teleop_base.RateCheck`).

    Args:
        config: Robot type, loop rate, key source, gripper start.
    """

    config_class = RmbKeyboardConfig
    name = "rmb_keyboard"

    def __init__(self, config: RmbKeyboardConfig):
        super().__init__(config)
        self.config = config
        self._keys = action_keys(config.robot, EE_VELOCITY_ACTIONS)
        gripper = single_arm_record(config.robot).arms[0].gripper
        self._gripper_range = gripper.command_range
        self._num_arms = 2 if config.robot == "rmb_ur5e_dual" else 1
        self.device = KeyboardDevice(
            num_arms=self._num_arms, gripper_step=gripper_step_for(self._gripper_range)
        )
        low, high = self._gripper_range
        start = min(max(float(config.gripper_start), low), high)
        self._gripper = [start] * self._num_arms
        self._source: KeySource | None = None
        self._router: StdinRouter | None = None
        self.rate_check = RateCheck(
            self.name,
            1.0 / float(config.fps),
            "set --teleop.fps to the loop's --fps and the robot's command_duration_s to 1 / --fps",
        )

    @property
    def is_connected(self) -> bool:
        """Whether a key source is open."""
        return self._source is not None

    def connect(self, calibrate: bool = True) -> None:
        """Open the key source (and take the terminal, see the module docstring).

        Args:
            calibrate: Ignored (nothing to calibrate).

        Raises:
            DeviceAlreadyConnectedError: Already connected.
            ConnectionError: No terminal and no display.
        """
        if self.is_connected:
            raise DeviceAlreadyConnectedError(f"{self} is already connected")
        self._source, self._router = open_key_source(self.config.keys)
        self.device.connect()
        self.rate_check.restart()

    def get_action(self) -> dict[str, Any]:
        """This step's action from the keys pressed since the last call.

        Returns:
            Every action key: twist (m/s, rad/s) and gripper command per arm.

        Raises:
            DeviceNotConnectedError: Not connected.
        """
        if self._source is None:
            raise DeviceNotConnectedError(f"{self} is not connected; call connect() first")
        self.rate_check.tick()
        keys = self._source.poll()
        if self._router is not None:
            self._router.forward(keys)
        return self.action_for(keys)

    def action_for(self, keys: list[str]) -> dict[str, float]:
        """The action for one step's key presses (what :meth:`get_action` returns).

        Args:
            keys: Key names, oldest first.

        Returns:
            Every action key with its value.
        """
        self.device.feed(keys)
        reading = self.device.read()
        fps = float(self.config.fps)
        low, high = self._gripper_range
        action: dict[str, float] = {}
        for arm in range(self._num_arms):
            prefix = f"{DUAL_SIDES[arm]}_" if self._num_arms > 1 else ""
            twist = [0.0] * 6
            delta = reading.arms.get(arm)
            if delta is not None:
                twist = [
                    *(float(v) * fps for v in delta.dpos),
                    *(float(v) * fps for v in delta.drpy),
                ]
                self._gripper[arm] = min(max(self._gripper[arm] + delta.dgripper, low), high)
            for key, value in zip(EE_VELOCITY_KEYS, twist, strict=True):
                action[prefix + key] = value
            action[prefix + GRIPPER_KEY] = float(self._gripper[arm])
        return action

    def disconnect(self) -> None:
        """Close the key source and give standard input back.

        Raises:
            DeviceNotConnectedError: Not connected.
        """
        if self._source is None:
            raise DeviceNotConnectedError(f"{self} is not connected")
        try:
            self._source.close()
            self.device.close()
        finally:
            if self._router is not None:
                self._router.close()
            self._source = self._router = None
