"""LeRobot teleoperators ``rmb_gello`` (joint space) and ``rmb_spacemouse`` (end effector).

Thin adapters from the teleop devices (:mod:`rmb_lerobot.envs.teleop.gello`,
:mod:`rmb_lerobot.envs.teleop.spacemouse`) to LeRobot's ``Teleoperator``, for the unmodified
``lerobot-teleoperate`` / ``lerobot-record`` on ``rmb_ur5e`` / ``rmb_xarm7`` and both arms of
``rmb_ur5e_dual`` (configs and why each emits what: :mod:`.config_teleop_devices`). Device
arm ``i`` drives the robot's arm ``i``; on the dual robot its keys carry that arm's prefix
(``left_``, ``right_``), as the robot's action features do. The device SDKs are imported in
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
    num_arms,
)
from rmb_lerobot.envs.real.lerobot_devices.features import (
    action_keys,
    single_arm_record,
)
from rmb_lerobot.envs.real.lerobot_devices.teleop_base import KeyedTeleoperator, RateCheck
from rmb_lerobot.envs.teleop.devices import spacemouse_paths
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
    """What both adapters share: the robot record (of one arm), the number of arms, connection
    state, no feedback."""

    def __init__(self, config: Any):
        super().__init__(config)
        self.config = config
        self.record = single_arm_record(config.robot)
        self.num_arms = num_arms(config.robot)
        arm = self.record.arms[0]
        self._gripper_open, self._gripper_closed = arm.gripper.open, arm.gripper.closed
        self._home = self.record.home_command()
        self._device: Any = None

    def _arm_keys(self, keys: tuple[str, ...]) -> list[tuple[str, ...]]:
        """The robot's keys (prefixed on the dual robot) cut into one tuple per arm."""
        per_arm = len(keys) // self.num_arms
        return [keys[i * per_arm : (i + 1) * per_arm] for i in range(self.num_arms)]

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
    (open .. closed), as RMB maps it onto the action bounds. On the dual robot a GELLO per
    arm (RMB's two-arm YAML): both must be ready before either moves.

    Args:
        config: Port, calibration, robot type, handover settings.
    """

    config_class = RmbGelloConfig
    name = "rmb_gello"

    def __init__(self, config: RmbGelloConfig):
        super().__init__(config)
        self._keys = action_keys(config.robot)
        self._per_arm_keys = self._arm_keys(self._keys)
        n = len(self.record.arms[0].joints)
        total = n * self.num_arms
        start = (
            np.tile(self._home[:n], self.num_arms)
            if config.start_joints is None
            else np.asarray(config.start_joints, dtype=np.float64)
        )
        if start.shape != (total,):
            raise ValueError(
                f"rmb_gello: start_joints has {start.size} values, {config.robot} has {total} "
                "arm joints"
            )
        self._starts = [start[i * n : (i + 1) * n].astype(np.float64) for i in range(self.num_arms)]
        self.arm_configs = self._arm_configs(n)
        self._ready = False
        self._last_log = 0.0

    @property
    def arm_config(self) -> GelloArmConfig:
        """The first (on a single-arm robot: the only) arm's GELLO."""
        return self.arm_configs[0]

    def _arm_configs(self, n: int) -> tuple[GelloArmConfig, ...]:
        config = self.config
        if config.rmb_config is not None:
            arms = load_rmb_gello_yaml(config.rmb_config).arms
            if len(arms) < self.num_arms:
                raise ValueError(
                    f"rmb_gello: {config.rmb_config} has {len(arms)} arm(s), {config.robot} "
                    f"needs {self.num_arms} (indices 0..{self.num_arms - 1})"
                )
            for index, arm in enumerate(arms[: self.num_arms]):
                if len(arm.joint_ids) != n:
                    raise ValueError(
                        f"rmb_gello: {config.rmb_config} arm {index} has {len(arm.joint_ids)} "
                        f"joints, each arm of {config.robot} has {n}"
                    )
            return tuple(arms[: self.num_arms])
        gripper = config.gripper
        arm = GelloArmConfig(
            port=str(config.port),
            joint_ids=tuple(config.joint_ids or range(1, n + 1)),
            joint_offsets=tuple(float(v) for v in config.joint_offsets or ()),
            joint_signs=tuple(int(s) for s in config.joint_signs or [1] * n),
            gripper=None if gripper is None else (int(gripper[0]), gripper[1], gripper[2]),
            baudrate=config.baudrate,
        )
        return (arm,)

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
                arms=self.arm_configs,
                start_joints=tuple(tuple(start) for start in self._starts),
                ready_tolerance_deg=self.config.ready_tolerance_deg,
                blend_steps=self.config.blend_steps,
            )
        )
        self._open_device(device)
        self._ready = False

    def _action(self, targets: list[tuple[np.ndarray, float]]) -> dict[str, float]:
        action: dict[str, float] = {}
        for keys, (joints, closure) in zip(self._per_arm_keys, targets, strict=True):
            gripper = self._gripper_open + closure * (self._gripper_closed - self._gripper_open)
            values = [*map(float, joints), float(gripper)]
            action |= dict(zip(keys, values, strict=True))
        return action

    def get_action(self) -> dict[str, Any]:
        """``start_joints`` until the GELLO is ready, then its (blended) pose.

        Returns:
            Every joint action key of the robot (both arms' on the dual robot).

        Raises:
            DeviceNotConnectedError: Not connected.
            ConnectionError: The servos stopped answering.
        """
        device: GelloDevice = self._require()
        if not self._ready:
            self._ready = device.is_ready(self._starts)
            if not self._ready:
                now = time.monotonic()
                if now - self._last_log >= NOT_READY_LOG_PERIOD_S:
                    log.warning("%s; holding the robot at start_joints", device.not_ready_reason)
                    self._last_log = now
                return self._action([(start, 0.0) for start in self._starts])
            log.info("GELLO ready: blending into its pose over %d steps", self.config.blend_steps)
        reading = device.read()
        return self._action(
            [(reading.arms[i].joints, reading.arms[i].gripper) for i in range(self.num_arms)]
        )


class RmbSpacemouse(_DeviceTeleop):
    """A SpaceMouse emitting an end-effector twist and the absolute gripper command.

    Keys: the robot's ``ee_velocity`` action keys (``ee_x.vel`` .. ``ee_yaw.vel``,
    ``gripper.pos``; per arm, prefixed, on the dual robot: one SpaceMouse each). The twist is
    RMB's per-step delta divided by ``command_duration_s``; the gripper command starts at
    ``gripper_start`` (default the record's home, open: the stock loops show a teleoperator
    no measured gripper) and moves by ``gripper_scale`` per step while a button is held,
    clipped to open .. closed. A warning names ``--fps`` and ``command_duration_s`` when the
    loop polls at another period than ``command_duration_s``.

    Args:
        config: Device path, scales, robot type, command duration.
    """

    config_class = RmbSpacemouseConfig
    name = "rmb_spacemouse"

    def __init__(self, config: RmbSpacemouseConfig):
        super().__init__(config)
        self._keys = action_keys(config.robot, EE_VELOCITY_ACTIONS)
        self._per_arm_keys = self._arm_keys(self._keys)
        self.paths = self._paths()
        self._grippers = self._gripper_start()
        self.rate_check = RateCheck(
            self.name,
            config.command_duration_s,
            "set --teleop.command_duration_s and the robot's command_duration_s to 1 / --fps",
        )

    def _paths(self) -> tuple[str, ...]:
        config = self.config
        if config.rmb_config is not None:
            paths = spacemouse_paths(config.rmb_config)
            if len(paths) < self.num_arms:
                raise ValueError(
                    f"rmb_spacemouse: {config.rmb_config} lists {len(paths)} device(s), "
                    f"{config.robot} needs {self.num_arms}"
                )
            return paths[: self.num_arms]
        if config.paths is not None:
            return tuple(config.paths)
        return () if config.path is None else (config.path,)

    def _gripper_start(self) -> list[float]:
        low, high = sorted((self._gripper_open, self._gripper_closed))
        start = self._home[-1] if self.config.gripper_start is None else self.config.gripper_start
        return [float(np.clip(start, low, high))] * self.num_arms

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
                paths=self.paths,
                pos_scale=config.pos_scale,
                rpy_scale=config.rpy_scale,
                gripper_scale=config.gripper_scale,
                reads_per_step=config.reads_per_step,
            )
        )
        self._open_device(device)
        self._grippers = self._gripper_start()
        self.rate_check.restart()

    def get_action(self) -> dict[str, Any]:
        """This step's twist and gripper command, per arm.

        Returns:
            ``ee_x.vel`` .. ``ee_yaw.vel`` (m/s, rad/s) and ``gripper.pos`` (prefixed per arm
            on the dual robot).

        Raises:
            DeviceNotConnectedError: Not connected.
        """
        device: SpaceMouseDevice = self._require()
        self.rate_check.tick()
        reading = device.read()
        low, high = sorted((self._gripper_open, self._gripper_closed))
        towards_closed = np.sign(self._gripper_closed - self._gripper_open)
        action: dict[str, float] = {}
        for arm, keys in enumerate(self._per_arm_keys):
            delta = reading.arms[arm]
            twist = np.concatenate([delta.dpos, delta.drpy]) / self.config.command_duration_s
            gripper = self._grippers[arm] + towards_closed * delta.dgripper
            self._grippers[arm] = float(np.clip(gripper, low, high))
            action |= dict(zip(keys, [*map(float, twist), self._grippers[arm]], strict=True))
        return action
