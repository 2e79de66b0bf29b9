"""``rmb_scripted``: a LeRobot teleoperator that replays a small joint motion, for tests and
dry runs of ``lerobot-record`` / ``lerobot-teleoperate`` without a device or an operator."""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
from lerobot.utils.errors import DeviceAlreadyConnectedError, DeviceNotConnectedError

from rmb_lerobot.envs.real.lerobot_devices.config import RmbScriptedConfig
from rmb_lerobot.envs.real.lerobot_devices.features import (
    GRIPPER_KEY,
    action_keys,
    home_vector,
    single_arm_record,
)
from rmb_lerobot.envs.real.lerobot_devices.teleop_base import KeyedTeleoperator


class RmbScripted(KeyedTeleoperator):
    """Emits every action key of its robot type: home, or a slow wave about home.

    The motion's clock starts at :meth:`connect`, so every run replays the same trajectory
    against wall time. The wave's fastest joint moves at ``2π · amplitude / period``
    (7.9 °/s with the defaults), far inside the safety layer's per-step clamp.

    Args:
        config: Which robot, which motion.
    """

    config_class = RmbScriptedConfig
    name = "rmb_scripted"

    def __init__(self, config: RmbScriptedConfig):
        super().__init__(config)
        self.config = config
        self._keys = action_keys(config.robot)
        home = home_vector(config.robot) if config.home is None else np.asarray(config.home)
        if home.shape != (len(self._keys),):
            raise ValueError(
                f"rmb_scripted: home has {home.size} values, {config.robot} has "
                f"{len(self._keys)} action keys {self._keys}"
            )
        self._home = home.astype(np.float64)
        gripper = single_arm_record(config.robot).arms[0].gripper
        self._gripper_open, self._gripper_closed = gripper.open, gripper.closed
        # Wave shape per key: alternate joints in opposite phase; the gripper separately.
        self._is_gripper = np.array([key.endswith(GRIPPER_KEY) for key in self._keys])
        signs = np.where(np.arange(len(self._keys)) % 2 == 0, 1.0, -1.0)
        self._signs = np.where(self._is_gripper, 0.0, signs)
        self._t0: float | None = None

    @property
    def is_connected(self) -> bool:
        """Whether :meth:`connect` started the script's clock."""
        return self._t0 is not None

    def connect(self, calibrate: bool = True) -> None:
        """Start the motion's clock.

        Args:
            calibrate: Ignored (nothing to calibrate).

        Raises:
            DeviceAlreadyConnectedError: Already connected.
        """
        if self.is_connected:
            raise DeviceAlreadyConnectedError(f"{self} is already connected")
        self._t0 = time.monotonic()

    def action_at(self, t: float) -> dict[str, float]:
        """The action ``t`` seconds after the start.

        Args:
            t: Time since :meth:`connect` (s).

        Returns:
            Every action key with its value.
        """
        values = self._home.copy()
        if self.config.motion == "wave":
            phase = 2.0 * math.pi * t / self.config.period_s
            values += self._signs * math.radians(self.config.amplitude_deg) * math.sin(phase)
            # Gripper: open -> half closed -> open once a period (from its home command).
            travel = 0.5 * (self._gripper_closed - self._gripper_open)
            values[self._is_gripper] += travel * 0.5 * (1.0 - math.cos(phase))
        return {key: float(v) for key, v in zip(self._keys, values, strict=True)}

    def get_action(self) -> dict[str, Any]:
        """The action for now.

        Returns:
            Every action key of the robot type with its value.

        Raises:
            DeviceNotConnectedError: Not connected.
        """
        if self._t0 is None:
            raise DeviceNotConnectedError(f"{self} is not connected; call connect() first")
        return self.action_at(time.monotonic() - self._t0)

    def disconnect(self) -> None:
        """Stop the clock.

        Raises:
            DeviceNotConnectedError: Not connected.
        """
        if self._t0 is None:
            raise DeviceNotConnectedError(f"{self} is not connected")
        self._t0 = None
