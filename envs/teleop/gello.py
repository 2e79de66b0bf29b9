"""GELLO leader arms as a joint-space input device (RMB's ``GelloInputDevice``).

A GELLO is a passive copy of the robot arm built from Dynamixel servos; its joint angles are
the robot's joint targets. Read with ``dynamixel-sdk`` (extra ``gello``), as gello's own
driver does: protocol 2.0, 57600 baud, present position at address 132 (4 bytes, signed),
``rad = raw / 2048 · π``, all servos of an arm in one GroupSyncRead. Per arm (RMB's
``Gello_*.yaml``): ``q = (rad - offset) · sign`` per joint; the gripper servo's angle maps
linearly from its open angle (0) to its closed angle (1), clipped.

Like gello's ``DynamixelRobot(start_joints=...)``, each offset is shifted by a multiple of
2π so that the device reads nearest the robot's joints at the start (the servos are
multi-turn; only the angle modulo 2π is calibrated). Then RMB's handover: the device
:meth:`GelloDevice.is_ready` only once every arm joint is within 30° of the robot's, and for
the next 50 steps the command blends linearly from the robot's joints into the device pose
(``c ← r · q + (1 - r) · c`` with ``r = k / 50``), so the robot is never yanked.

Construct with a :class:`GelloConfig` (the teleop loop does this by module path,
``rmb_lerobot.envs.teleop.gello.GelloDevice``); :func:`load_rmb_gello_yaml` reads RMB's
config files.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rmb_lerobot.envs.teleop.device import DeviceReading, InputDevice, JointTarget

log = logging.getLogger(__name__)

PROTOCOL_VERSION = 2.0
BAUDRATE = 57600
ADDR_TORQUE_ENABLE = 64
ADDR_PRESENT_POSITION = 132
LEN_PRESENT_POSITION = 4
COUNTS_PER_HALF_TURN = 2048.0
READY_TOLERANCE_DEG = 30.0
BLEND_STEPS = 50
READ_RETRIES = 5
"""Tries per read or ping: a status packet lost on the bus (or a late one, which the SDK
drops after its ~35 ms timeout) must not end a demonstration."""
INSTALL_HINT = (
    "GELLO needs dynamixel-sdk: pip install 'lerobot_env_rmb[gello]' (or uv sync --extra gello)"
)


@dataclass(frozen=True)
class GelloArmConfig:
    """One GELLO arm (one serial adapter), in RMB's ``Gello_*.yaml`` terms.

    Attributes:
        port: The serial adapter (``/dev/serial/by-id/usb-FTDI_...``, ``/dev/ttyUSB0``).
        joint_ids: Servo ID of each arm joint, in the robot's joint order.
        joint_offsets: Per joint, the servo angle (rad) at the robot's zero.
        joint_signs: Per joint, +1 or -1 (the servo turns the other way).
        gripper: ``(servo ID, open angle, closed angle)`` in degrees, or None (no gripper
            servo: the device reports the gripper open).
        baudrate: The bus's baud rate (GELLO's servos run at 57600).
    """

    port: str
    joint_ids: tuple[int, ...]
    joint_offsets: tuple[float, ...]
    joint_signs: tuple[int, ...]
    gripper: tuple[int, float, float] | None = None
    baudrate: int = BAUDRATE

    def __post_init__(self) -> None:
        n = len(self.joint_ids)
        if n == 0:
            raise ValueError(f"GELLO arm on {self.port}: joint_ids is empty")
        if len(self.joint_offsets) != n or len(self.joint_signs) != n:
            raise ValueError(
                f"GELLO arm on {self.port}: {n} joint_ids but {len(self.joint_offsets)} "
                f"joint_offsets and {len(self.joint_signs)} joint_signs (expected one each)"
            )
        if any(sign not in (1, -1) for sign in self.joint_signs):
            raise ValueError(
                f"GELLO arm on {self.port}: joint_signs must be 1 or -1, got {self.joint_signs}"
            )
        ids = [*self.joint_ids, *([self.gripper[0]] if self.gripper else [])]
        if len(set(ids)) != len(ids) or any(not 0 <= i <= 252 for i in ids):
            raise ValueError(
                f"GELLO arm on {self.port}: servo IDs must be distinct and in 0..252, got {ids}"
            )
        if self.gripper is not None and self.gripper[1] == self.gripper[2]:
            raise ValueError(
                f"GELLO arm on {self.port}: gripper open and closed angles are both "
                f"{self.gripper[1]} deg"
            )
        if not all(math.isfinite(v) for v in self.joint_offsets):
            raise ValueError(f"GELLO arm on {self.port}: joint_offsets must be finite")

    @property
    def servo_ids(self) -> tuple[int, ...]:
        """Every servo read, arm joints first, then the gripper."""
        return (*self.joint_ids, *((self.gripper[0],) if self.gripper else ()))


@dataclass(frozen=True)
class GelloConfig:
    """The GELLO device: one :class:`GelloArmConfig` per robot arm, in record order.

    Attributes:
        arms: The arms (arm 0 drives the robot record's first arm).
        start_joints: Per arm, the robot's joints (rad) to align the 2π offsets to at
            :meth:`GelloDevice.connect` (RMB passes the command at start); None: align at the
            first :meth:`GelloDevice.is_ready` call, to the measured joints given there.
        ready_tolerance_deg: Every arm joint must be this close to the robot's to start.
        blend_steps: Steps of the linear blend from the robot's joints into the device pose.
        smoothing: gello's exponential smoothing, the weight of a new reading (1: none).
    """

    arms: tuple[GelloArmConfig, ...]
    start_joints: tuple[tuple[float, ...], ...] | None = None
    ready_tolerance_deg: float = READY_TOLERANCE_DEG
    blend_steps: int = BLEND_STEPS
    smoothing: float = 0.99

    def __post_init__(self) -> None:
        if not self.arms:
            raise ValueError("GelloConfig needs at least one arm")
        if self.start_joints is not None:
            if len(self.start_joints) != len(self.arms):
                raise ValueError(
                    f"GelloConfig: {len(self.start_joints)} start_joints for "
                    f"{len(self.arms)} arms (expected one vector per arm)"
                )
            for arm, start in zip(self.arms, self.start_joints, strict=True):
                if len(start) != len(arm.joint_ids):
                    raise ValueError(
                        f"GELLO arm on {arm.port}: start_joints has {len(start)} values for "
                        f"{len(arm.joint_ids)} joints"
                    )
        if not 0 < self.ready_tolerance_deg <= 180 or self.blend_steps < 0:
            raise ValueError(
                "GelloConfig: needs 0 < ready_tolerance_deg <= 180 and blend_steps >= 0, got "
                f"{self.ready_tolerance_deg} and {self.blend_steps}"
            )
        if not 0 < self.smoothing <= 1:
            raise ValueError(f"GelloConfig: smoothing must be in (0, 1], got {self.smoothing}")


def load_rmb_gello_yaml(path: str | Path) -> GelloConfig:
    """Read an RMB GELLO config (``{0: {port, config: {joint_ids, joint_offsets,
    joint_signs, gripper_config}}, 1: ...}``), one entry per arm.

    Args:
        path: The YAML file (RMB's ``teleop/configs/Gello_*.yaml`` format).

    Returns:
        The device config, arms in index order.

    Raises:
        ValueError: A missing or malformed entry (the message names the file and key).
    """
    import yaml

    path = Path(path)
    data = yaml.safe_load(path.read_text())
    if not isinstance(data, dict) or not data:
        raise ValueError(f"{path}: expected a mapping of arm index -> {{port, config}}")
    arms = []
    for index in sorted(data):
        entry = data[index]
        try:
            config = entry["config"]
            gripper = config.get("gripper_config")
            arms.append(
                GelloArmConfig(
                    port=str(entry["port"]),
                    joint_ids=tuple(int(i) for i in config["joint_ids"]),
                    joint_offsets=tuple(float(v) for v in config["joint_offsets"]),
                    joint_signs=tuple(int(s) for s in config["joint_signs"]),
                    gripper=(
                        None
                        if gripper is None
                        else (int(gripper[0]), float(gripper[1]), float(gripper[2]))
                    ),
                )
            )
        except (KeyError, TypeError, IndexError) as error:
            raise ValueError(
                f"{path}: arm {index} needs port and config.joint_ids / joint_offsets / "
                f"joint_signs (and optionally gripper_config [id, open_deg, closed_deg]): "
                f"{error!r}"
            ) from error
    return GelloConfig(arms=tuple(arms))


def raw_to_rad(raw: int) -> float:
    """A present-position count (signed 32-bit) in radians, as gello's driver converts it."""
    raw = int(raw)
    if raw > 0x7FFFFFFF:
        raw -= 0x100000000
    return raw / COUNTS_PER_HALF_TURN * math.pi


def aligned_offsets(
    servo_rad: np.ndarray, offsets: np.ndarray, signs: np.ndarray, start: np.ndarray
) -> np.ndarray:
    """Shift each offset by a multiple of 2π so that the joint reads nearest ``start``.

    Args:
        servo_rad: The arm joints' servo angles now (rad).
        offsets: Their calibrated offsets (rad).
        signs: Their signs.
        start: The robot's joints to be nearest to (rad).

    Returns:
        The shifted offsets: ``(servo_rad - offset) · sign`` is within π of ``start``.
    """
    q = (servo_rad - offsets) * signs
    turns = np.round((start - q) / (2 * np.pi))
    # q' = (servo - (offset - sign·2πk)) · sign = q + 2πk.
    return offsets - signs * 2 * np.pi * turns


@dataclass
class _ArmBus:
    """An arm's open port and its sync reader (SDK objects)."""

    config: GelloArmConfig
    port: Any
    packet: Any
    reader: Any
    offsets: np.ndarray
    signs: np.ndarray
    last: np.ndarray | None = None  # smoothed [joints..., gripper 0..1]
    blend_from: np.ndarray | None = None  # the command the blend runs from (None: no blend)
    blend_step: int = 0
    aligned: bool = False


class GelloDevice(InputDevice):
    """GELLO leader arms: joint targets per arm (:class:`JointTarget`).

    Args:
        config: The arms, their ports and calibration, readiness and blend settings.
    """

    name = "gello"

    def __init__(self, config: GelloConfig):
        self.config = config
        self._buses: list[_ArmBus] = []
        self._sdk: Any = None
        self.not_ready_reason = ""
        """Why the last :meth:`is_ready` said no (which joints, how far), for display."""

    @property
    def is_connected(self) -> bool:
        """Whether every arm's port is open."""
        return bool(self._buses)

    # ------------------------------------------------------------------ lifecycle
    def connect(self) -> None:
        """Open each arm's port at its baud rate, check every servo answers, torque off.

        Raises:
            ImportError: dynamixel-sdk is not installed (extra ``gello``).
            ConnectionError: A port cannot be opened, or a servo does not answer (the
                message names the port and the silent IDs).
        """
        if self._buses:
            return
        try:
            import dynamixel_sdk
        except ImportError as error:
            raise ImportError(INSTALL_HINT) from error
        self._sdk = dynamixel_sdk
        try:
            for arm in self.config.arms:
                self._buses.append(self._open(arm))
            if self.config.start_joints is not None:
                self.align([np.asarray(s, dtype=np.float64) for s in self.config.start_joints])
        except BaseException:
            self.close()
            raise

    def _open(self, arm: GelloArmConfig) -> _ArmBus:
        sdk = self._sdk
        port = sdk.PortHandler(arm.port)
        try:
            opened = port.openPort() and port.setBaudRate(arm.baudrate)
        except Exception as error:  # pyserial's SerialException, OSError
            raise ConnectionError(f"GELLO: cannot open serial port {arm.port}: {error}") from error
        if not opened:
            raise ConnectionError(f"GELLO: cannot open {arm.port} at {arm.baudrate} baud")
        packet = sdk.PacketHandler(PROTOCOL_VERSION)
        bus = _ArmBus(
            config=arm,
            port=port,
            packet=packet,
            reader=None,
            offsets=np.asarray(arm.joint_offsets, dtype=np.float64),
            signs=np.asarray(arm.joint_signs, dtype=np.float64),
        )
        try:
            silent = [i for i in arm.servo_ids if not self._ping(packet, port, i)]
            if silent:
                raise ConnectionError(
                    f"GELLO: no answer from servo IDs {silent} on {arm.port} (protocol 2.0, "
                    f"{arm.baudrate} baud); check the IDs in the config, the power and the cable"
                )
            # A leader arm is moved by hand: make sure no servo holds its position.
            for dxl_id in arm.servo_ids:
                packet.write1ByteTxRx(port, dxl_id, ADDR_TORQUE_ENABLE, 0)
            reader = sdk.GroupSyncRead(port, packet, ADDR_PRESENT_POSITION, LEN_PRESENT_POSITION)
            for dxl_id in arm.servo_ids:
                reader.addParam(dxl_id)
            bus.reader = reader
        except BaseException:
            port.closePort()
            raise
        return bus

    def _ping(self, packet: Any, port: Any, dxl_id: int) -> bool:
        """Whether a servo answers a PING within :data:`READ_RETRIES` tries."""
        return any(
            packet.ping(port, dxl_id)[1] == self._sdk.COMM_SUCCESS for _ in range(READ_RETRIES)
        )

    def close(self) -> None:
        """Close every port (safe to call twice)."""
        buses, self._buses = self._buses, []
        for bus in buses:
            try:
                bus.port.closePort()
            except Exception as error:  # closing must not hide what made us close
                log.warning("GELLO: closing %s failed: %s", bus.config.port, error)

    # ------------------------------------------------------------------ reading
    def _servo_rad(self, bus: _ArmBus) -> np.ndarray:
        """One GroupSyncRead of an arm: every servo's angle (rad), in ``servo_ids`` order."""
        sdk = self._sdk
        result = sdk.COMM_SUCCESS
        for _ in range(READ_RETRIES):
            result = bus.reader.txRxPacket()
            if result == sdk.COMM_SUCCESS:
                break
        else:
            raise ConnectionError(
                f"GELLO: reading servos {list(bus.config.servo_ids)} on {bus.config.port} "
                f"failed {READ_RETRIES} times: {bus.packet.getTxRxResult(result)}"
            )
        values = []
        for dxl_id in bus.config.servo_ids:
            if not bus.reader.isAvailable(dxl_id, ADDR_PRESENT_POSITION, LEN_PRESENT_POSITION):
                raise ConnectionError(
                    f"GELLO: servo {dxl_id} on {bus.config.port} sent no present position"
                )
            values.append(
                raw_to_rad(bus.reader.getData(dxl_id, ADDR_PRESENT_POSITION, LEN_PRESENT_POSITION))
            )
        return np.asarray(values, dtype=np.float64)

    def _pose(self, bus: _ArmBus) -> np.ndarray:
        """The arm's device pose now: joints (rad) then the gripper closure (0..1), smoothed."""
        rad = self._servo_rad(bus)
        n = len(bus.config.joint_ids)
        joints = (rad[:n] - bus.offsets) * bus.signs
        gripper = 0.0
        if bus.config.gripper is not None:
            _, open_deg, closed_deg = bus.config.gripper
            opened, closed = math.radians(open_deg), math.radians(closed_deg)
            gripper = float(np.clip((rad[n] - opened) / (closed - opened), 0.0, 1.0))
        pose = np.append(joints, gripper)
        alpha = self.config.smoothing
        if bus.last is not None and alpha < 1.0:
            pose = bus.last * (1.0 - alpha) + pose * alpha
        bus.last = pose
        return pose

    def _require(self) -> None:
        if not self._buses:
            raise RuntimeError("GELLO is not connected; call connect() first")

    def align(self, start_joints: Sequence[np.ndarray]) -> None:
        """Shift every arm's offsets by multiples of 2π to read nearest ``start_joints``.

        Args:
            start_joints: Per arm, the robot's joints (rad).

        Raises:
            ValueError: Wrong number of arms or joints.
        """
        self._require()
        if len(start_joints) != len(self._buses):
            raise ValueError(
                f"GELLO: {len(start_joints)} joint vectors for {len(self._buses)} arms"
            )
        for bus, start in zip(self._buses, start_joints, strict=True):
            start = np.asarray(start, dtype=np.float64)
            n = len(bus.config.joint_ids)
            if start.shape != (n,):
                raise ValueError(
                    f"GELLO arm on {bus.config.port}: {start.size} joints given, it has {n}"
                )
            rad = self._servo_rad(bus)[:n]
            bus.offsets = aligned_offsets(rad, bus.offsets, bus.signs, start)
            bus.aligned = True
            bus.last = None

    def joint_errors(self, measured_joints: Sequence[np.ndarray]) -> list[np.ndarray]:
        """Per arm, ``|device - robot|`` per joint (rad), aligning offsets first if needed.

        Args:
            measured_joints: Each arm's joints (rad), in record order.

        Returns:
            The absolute differences per arm.
        """
        self._require()
        if not all(bus.aligned for bus in self._buses):
            self.align(measured_joints)
        errors = []
        for bus, measured in zip(self._buses, measured_joints, strict=True):
            n = len(bus.config.joint_ids)
            errors.append(np.abs(self._pose(bus)[:n] - np.asarray(measured, dtype=np.float64)))
        return errors

    def is_ready(self, measured_joints: Sequence[np.ndarray]) -> bool:
        """Whether every arm joint is within the tolerance (30°) of the robot's.

        When it is, the blend restarts from ``measured_joints``: the next
        ``blend_steps`` readings move linearly from there into the device pose. The
        gripper is not blended (the measured joints carry none): it follows the device.

        Args:
            measured_joints: Each arm's measured joint positions (rad), in record order.

        Returns:
            True when the device may drive the robot.
        """
        errors = self.joint_errors(measured_joints)
        tolerance = math.radians(self.config.ready_tolerance_deg)
        far = {
            (arm, j): math.degrees(e)
            for arm, err in enumerate(errors)
            for j, e in enumerate(err)
            if e >= tolerance
        }
        if far:
            listed = ", ".join(f"arm {a} joint {j}: {d:.0f} deg" for (a, j), d in far.items())
            self.not_ready_reason = (
                f"GELLO is not ready: move it to the robot's pose ({listed} away; the limit is "
                f"{self.config.ready_tolerance_deg:.0f} deg)"
            )
            log.debug(self.not_ready_reason)
            return False
        self.not_ready_reason = ""
        for bus, measured in zip(self._buses, measured_joints, strict=True):
            start = np.append(np.asarray(measured, dtype=np.float64), bus.last[-1])
            bus.blend_from = start if self.config.blend_steps > 0 else None
            bus.blend_step = 0
        return True

    def read(self) -> DeviceReading:
        """Every arm's joint target: the device pose, blended in after :meth:`is_ready`.

        Returns:
            A :class:`JointTarget` per arm (joints in rad, gripper 0 open .. 1 closed).

        Raises:
            RuntimeError: Not connected.
            ConnectionError: The servos stopped answering (after :data:`READ_RETRIES` tries
                of about 35 ms each, the SDK's status timeout at 57600 baud).
        """
        self._require()
        arms: dict[int, JointTarget] = {}
        for index, bus in enumerate(self._buses):
            pose = self._pose(bus)
            command = pose
            if bus.blend_from is not None and bus.blend_step < self.config.blend_steps:
                ratio = bus.blend_step / self.config.blend_steps
                command = ratio * pose + (1.0 - ratio) * bus.blend_from
                bus.blend_from = command
                bus.blend_step += 1
            arms[index] = JointTarget(joints=command[:-1].copy(), gripper=float(command[-1]))
        return DeviceReading(arms=arms)

    def blending(self) -> bool:
        """Whether any arm is still inside its handover blend."""
        return any(
            bus.blend_from is not None and bus.blend_step < self.config.blend_steps
            for bus in self._buses
        )
