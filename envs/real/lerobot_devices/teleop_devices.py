"""LeRobot teleoperators ``rmb_gello`` (joint space) and ``rmb_spacemouse`` (end effector).

Thin adapters from the teleop devices (:mod:`rmb_lerobot.envs.teleop.gello`,
:mod:`rmb_lerobot.envs.teleop.spacemouse`) to LeRobot's ``Teleoperator``, for the unmodified
``lerobot-teleoperate`` / ``lerobot-record`` on ``rmb_ur5e`` / ``rmb_xarm7`` (configs and
why each emits what: :mod:`.config_teleop_devices`). The device SDKs are imported in
``connect``, so building either (``lerobot-record`` reads features first) needs no extra.
"""

from __future__ import annotations

import logging
import time
from typing import Any

import numpy as np
from lerobot.utils.errors import DeviceAlreadyConnectedError, DeviceNotConnectedError

from rmb_lerobot.envs.real.lerobot_devices.config import EE_VELOCITY_ACTIONS
from rmb_lerobot.envs.real.lerobot_devices.config_teleop_devices import (
    RmbGelloConfig,
    RmbSpacemouseConfig,
)
from rmb_lerobot.envs.real.lerobot_devices.features import (
    arm_action_keys,
    arm_keys,
    single_arm_record,
)
from rmb_lerobot.envs.real.lerobot_devices.teleop_base import KeyedTeleoperator
from rmb_lerobot.envs.teleop.gello import (
    GelloArmConfig,
    GelloConfig,
    GelloDevice,
    load_rmb_gello_yaml,
)
from rmb_lerobot.envs.teleop.spacemouse import SpaceMouseConfig, SpaceMouseDevice

log = logging.getLogger(__name__)

NOT_READY_LOG_PERIOD_S = 2.0


class _DeviceTeleop(KeyedTeleoperator):
    """What both adapters share: the robot record, connection state, no feedback."""

    def __init__(self, config: Any):
        super().__init__(config)
        self.config = config
        self.record = single_arm_record(config.robot)
        arm = self.record.arms[0]
        self._gripper_open, self._gripper_closed = arm.gripper.open, arm.gripper.closed
        self._home = self.record.home_command()
        self._device: Any = None

    @property
    def is_connected(self) -> bool:
        """Whether the device is open."""
        return self._device is not None

    def _open_device(self, device: Any) -> None:
        if self.is_connected:
            raise DeviceAlreadyConnectedError(f"{self} is already connected")
        device.connect()
        self._device = device

    def _require(self) -> Any:
        if self._device is None:
            raise DeviceNotConnectedError(f"{self} is not connected; call connect() first")
        return self._device

    def disconnect(self) -> None:
        """Close the device.

        Raises:
            DeviceNotConnectedError: Not connected.
        """
        device = self._require()
        self._device = None
        device.close()


class RmbGello(_DeviceTeleop):
    """A GELLO leader arm emitting the robot's joint action (``<joint>.pos``, ``gripper.pos``).

    Until the GELLO is within ``ready_tolerance_deg`` of ``start_joints`` it emits
    ``start_joints`` (the robot holds); then the device's 50-step blend hands over to the
    GELLO pose. The gripper closure (0..1) maps linearly onto the robot's gripper command
    (open .. closed), as RMB maps it onto the action bounds.

    Args:
        config: Port, calibration, robot type, handover settings.
    """

    config_class = RmbGelloConfig
    name = "rmb_gello"

    def __init__(self, config: RmbGelloConfig):
        super().__init__(config)
        self._keys = arm_keys(self.record)
        n = len(self.record.arms[0].joints)
        start = self._home[:n] if config.start_joints is None else np.asarray(config.start_joints)
        if start.shape != (n,):
            raise ValueError(
                f"rmb_gello: start_joints has {start.size} values, {config.robot} has {n} joints"
            )
        self._start = start.astype(np.float64)
        self.arm_config = self._arm_config(n)
        self._ready = False
        self._last_log = 0.0

    def _arm_config(self, n: int) -> GelloArmConfig:
        config = self.config
        if config.rmb_config is not None:
            arm = load_rmb_gello_yaml(config.rmb_config).arms[0]
            if len(arm.joint_ids) != n:
                raise ValueError(
                    f"rmb_gello: {config.rmb_config} arm 0 has {len(arm.joint_ids)} joints, "
                    f"{config.robot} has {n}"
                )
            return arm
        gripper = config.gripper
        return GelloArmConfig(
            port=str(config.port),
            joint_ids=tuple(config.joint_ids or range(1, n + 1)),
            joint_offsets=tuple(float(v) for v in config.joint_offsets or ()),
            joint_signs=tuple(int(s) for s in config.joint_signs or [1] * n),
            gripper=None if gripper is None else (int(gripper[0]), gripper[1], gripper[2]),
            baudrate=config.baudrate,
        )

    @property
    def ready(self) -> bool:
        """Whether the GELLO has taken over from ``start_joints``."""
        return self._ready

    def connect(self, calibrate: bool = True) -> None:
        """Open the GELLO and align its offsets to ``start_joints``.

        Args:
            calibrate: Ignored (the offsets are the calibration).

        Raises:
            DeviceAlreadyConnectedError: Already connected.
            ImportError: dynamixel-sdk is missing (extra ``gello``).
            ConnectionError: The port or a servo does not answer.
        """
        device = GelloDevice(
            GelloConfig(
                arms=(self.arm_config,),
                start_joints=(tuple(self._start),),
                ready_tolerance_deg=self.config.ready_tolerance_deg,
                blend_steps=self.config.blend_steps,
            )
        )
        self._open_device(device)
        self._ready = False

    def _action(self, joints: np.ndarray, closure: float) -> dict[str, float]:
        gripper = self._gripper_open + closure * (self._gripper_closed - self._gripper_open)
        values = [*map(float, joints), float(gripper)]
        return dict(zip(self._keys, values, strict=True))

    def get_action(self) -> dict[str, Any]:
        """``start_joints`` until the GELLO is ready, then its (blended) pose.

        Returns:
            Every joint action key of the robot.

        Raises:
            DeviceNotConnectedError: Not connected.
            ConnectionError: The servos stopped answering.
        """
        device: GelloDevice = self._require()
        if not self._ready:
            self._ready = device.is_ready([self._start])
            if not self._ready:
                now = time.monotonic()
                if now - self._last_log >= NOT_READY_LOG_PERIOD_S:
                    log.warning("%s; holding the robot at start_joints", device.not_ready_reason)
                    self._last_log = now
                return self._action(self._start, 0.0)
            log.info("GELLO ready: blending into its pose over %d steps", self.config.blend_steps)
        target = device.read().arms[0]
        return self._action(target.joints, target.gripper)


class RmbSpacemouse(_DeviceTeleop):
    """A SpaceMouse emitting an end-effector twist and the absolute gripper command.

    Keys: the robot's ``ee_velocity`` action keys (``ee_x.vel`` .. ``ee_yaw.vel``,
    ``gripper.pos``). The twist is RMB's per-step delta divided by ``command_duration_s``;
    the gripper command starts at the robot record's home (open) and moves by
    ``gripper_scale`` per step while a button is held, clipped to open .. closed.

    Args:
        config: Device path, scales, robot type, command duration.
    """

    config_class = RmbSpacemouseConfig
    name = "rmb_spacemouse"

    def __init__(self, config: RmbSpacemouseConfig):
        super().__init__(config)
        self._keys = arm_action_keys(self.record, EE_VELOCITY_ACTIONS)
        self._gripper = float(self._home[-1])

    def connect(self, calibrate: bool = True) -> None:
        """Open the SpaceMouse; the gripper command starts at the record's home.

        Args:
            calibrate: Ignored.

        Raises:
            DeviceAlreadyConnectedError: Already connected.
            ImportError: pyspacemouse is missing (extra ``spacemouse``).
            ConnectionError: hidapi is missing or the device is absent.
        """
        config = self.config
        device = SpaceMouseDevice(
            SpaceMouseConfig(
                paths=() if config.path is None else (config.path,),
                pos_scale=config.pos_scale,
                rpy_scale=config.rpy_scale,
                gripper_scale=config.gripper_scale,
                reads_per_step=config.reads_per_step,
            )
        )
        self._open_device(device)
        self._gripper = float(self._home[-1])

    def get_action(self) -> dict[str, Any]:
        """This step's twist and gripper command.

        Returns:
            ``ee_x.vel`` .. ``ee_yaw.vel`` (m/s, rad/s) and ``gripper.pos``.

        Raises:
            DeviceNotConnectedError: Not connected.
        """
        device: SpaceMouseDevice = self._require()
        delta = device.read().arms[0]
        twist = np.concatenate([delta.dpos, delta.drpy]) / self.config.command_duration_s
        low, high = sorted((self._gripper_open, self._gripper_closed))
        towards_closed = np.sign(self._gripper_closed - self._gripper_open)
        self._gripper = float(np.clip(self._gripper + towards_closed * delta.dgripper, low, high))
        return dict(zip(self._keys, [*map(float, twist), self._gripper], strict=True))
