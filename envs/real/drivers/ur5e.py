"""UR5e + Robotiq 2F-85 driver: ur-rtde for the arm, the URCap socket for the gripper.

The calls are RMB's (``RealUR5eEnvBase``): ``RTDEControlInterface(ip)`` and
``RTDEReceiveInterface(ip)``, ``endFreedriveMode()``; a joint command is one
``servoJ(q, 0.5, 0.5, duration, 0.2, 100)`` inside ``initPeriod()`` / ``waitPeriod()``;
readings are ``getActualQ``, ``getActualQd``, ``getActualTCPForce``; ``zeroFtSensor()`` zeroes
the wrench. The gripper is RMB's Robotiq 2F-85 on the controller's URCap socket
(:class:`~rmb_lerobot.envs.real.drivers.robotiq.RobotiqGripper`), moved with RMB's speed 50 and
force 10, its position 0 (open) .. 255 (closed) being the gripper command's units.

``driver: sdk`` imports ur-rtde (the ``ur5e`` extra) when :meth:`UR5eDriver.connect` runs;
``driver: sim`` talks to a :class:`~rmb_lerobot.envs.real.twins.ur5e.UR5eTwin` instead, through
the same calls.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from rmb_lerobot.envs.real.driver import (
    ArmState,
    ConnectionLost,
    DriverError,
    ProtectiveStop,
)
from rmb_lerobot.envs.real.drivers.common import (
    DriverKind,
    StaleWatch,
    check_driver_config,
    import_sdk,
)
from rmb_lerobot.envs.real.drivers.robotiq import URCAP_PORT, RobotiqGripper

if TYPE_CHECKING:
    from rmb_lerobot.envs.real.twins.ur5e import UR5eTwin

log = logging.getLogger(__name__)

NUM_JOINTS = 6
# RMB's servoJ arguments besides q and the duration: speed, acceleration (unused by servoJ),
# lookahead time (s) and gain.
SERVO_SPEED, SERVO_ACCEL, SERVO_LOOKAHEAD, SERVO_GAIN = 0.5, 0.5, 0.2, 100.0
STOP_DECELERATION = 2.0  # rad/s^2, stopJ's deceleration (ur-rtde's default)
GRIPPER_SPEED, GRIPPER_FORCE = 50, 10  # RMB's gripper move(pos, speed 50, force 10)

# ur-rtde's SafetyMode values in which the arm is stopped (others: 1 normal, 2 reduced,
# 4 recovery, 10 validate joint id, 11 undefined).
STOPPED_SAFETY_MODES: dict[int, str] = {
    3: "PROTECTIVE_STOP",
    5: "SAFEGUARD_STOP",
    6: "SYSTEM_EMERGENCY_STOP",
    7: "ROBOT_EMERGENCY_STOP",
    8: "VIOLATION",
    9: "FAULT",
    12: "AUTOMATIC_MODE_SAFEGUARD_STOP",
    13: "SYSTEM_THREE_POSITION_ENABLING_STOP",
}

_UR_RTDE_NOTE = (
    "ur-rtde 1.6 ships wheels for CPython 3.12 on Linux x86_64 and Windows x64 only; "
    "elsewhere build it from its source distribution (CMake, Boost)"
)


@dataclass
class UR5eConfig:
    """How to reach one UR5e with its Robotiq 2F-85.

    Attributes:
        host: The UR controller's address (no default: write your arm's address; ``sim``
            needs a loopback address such as ``127.0.0.1``).
        driver: ``"sdk"`` drives the arm with ur-rtde; ``"sim"`` drives the MuJoCo twin.
        gripper_port: The Robotiq URCap socket's port (``sdk``; the twin picks a free one).
        gripper_speed: Robotiq speed 0..255 of every gripper move (RMB: 50).
        gripper_force: Robotiq force 0..255 of every gripper move (RMB: 10).
        socket_timeout_s: Timeout (s) of the gripper socket, per request.
        activation_timeout_s: How long gripper activation may take.
        stale_after_s: How long the controller timestamp may stay unchanged before a reading
            counts as stale (the RTDE stream runs at 500 Hz).
    """

    host: str
    driver: DriverKind = "sim"
    gripper_port: int = URCAP_PORT
    gripper_speed: int = GRIPPER_SPEED
    gripper_force: int = GRIPPER_FORCE
    socket_timeout_s: float = 2.0
    activation_timeout_s: float = 5.0
    stale_after_s: float = 0.5


class UR5eDriver:
    """One UR5e with a Robotiq 2F-85 (:class:`~rmb_lerobot.envs.real.driver.ArmDriver`).

    A context manager: leaving the ``with`` block (also by an exception or Ctrl-C) stops the
    arm and disconnects.

    Args:
        config: Where the arm is and which driver talks to it.
        twin: With ``driver: sim``, the twin to talk to (default: the driver starts its own
            and closes it in :meth:`close`).
    """

    def __init__(self, config: UR5eConfig, twin: UR5eTwin | None = None):
        check_driver_config("UR5e", config.driver, config.host)
        if twin is not None and config.driver != "sim":
            raise ValueError("UR5eDriver: a twin is only used with driver 'sim'")
        self.config = config
        self.name = f"UR5e at {config.host}"
        self._twin = twin
        self._own_twin = False
        self._ctrl: Any = None
        self._recv: Any = None
        self._gripper: RobotiqGripper | None = None
        self._stale = StaleWatch(self.name, config.stale_after_s)

    @property
    def twin(self) -> UR5eTwin | None:
        """The twin this driver talks to (``driver: sim``), else ``None``."""
        return self._twin

    # ------------------------------------------------------------------ connection
    def connect(self) -> None:
        """Connect to the arm and the gripper, end freedrive, activate the gripper.

        Raises:
            ImportError: If ``driver: sdk`` and ur-rtde is not installed (naming the extra).
            ConnectionLost: If the controller or the gripper socket does not answer.
            GripperFault: If the gripper does not activate.
        """
        self.close()
        cfg = self.config
        if cfg.driver == "sim":
            if self._twin is None:
                from rmb_lerobot.envs.real.twins.ur5e import UR5eTwin

                self._twin, self._own_twin = UR5eTwin(cfg.host), True
            make_control = self._twin.RTDEControlInterface
            make_receive = self._twin.RTDEReceiveInterface
            gripper_port = self._twin.gripper_port
        else:
            make_control = import_sdk("rtde_control", "ur5e", _UR_RTDE_NOTE).RTDEControlInterface
            make_receive = import_sdk("rtde_receive", "ur5e", _UR_RTDE_NOTE).RTDEReceiveInterface
            gripper_port = cfg.gripper_port
        try:
            try:
                self._ctrl = make_control(cfg.host)
                self._recv = make_receive(cfg.host)
            except RuntimeError as error:
                raise ConnectionLost(f"{self.name}: cannot connect over RTDE: {error}") from error
            self._call("endFreedriveMode", self._ctrl.endFreedriveMode)
            self._gripper = RobotiqGripper(cfg.host, gripper_port, cfg.socket_timeout_s)
            self._gripper.connect()
            self._gripper.activate(timeout_s=cfg.activation_timeout_s)
            self._gripper.check_fault()
        except BaseException:
            self.close()
            raise
        self._stale.reset()

    def __enter__(self) -> UR5eDriver:
        self.connect()
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    def _require(self) -> None:
        if self._ctrl is None or self._recv is None or self._gripper is None:
            raise ConnectionLost(f"{self.name}: not connected (call connect() first)")

    def _link_down(self) -> bool:
        try:
            return not (self._recv.isConnected() and self._ctrl.isConnected())
        except RuntimeError:
            return True

    def _call(self, name: str, function: Any, *args: Any) -> Any:
        """Call an SDK function, turning its exceptions into :class:`DriverError`."""
        try:
            return function(*args)
        except RuntimeError as error:
            if self._link_down():
                raise ConnectionLost(
                    f"{self.name}: connection lost during {name}: {error}"
                ) from error
            raise DriverError(f"{self.name}: {name} failed: {error}") from error

    def _check_running(self, call: str) -> None:
        """Raise if the controller is unreachable or has stopped the arm."""
        if self._link_down():
            raise ConnectionLost(f"{self.name}: RTDE connection lost ({call})")
        mode = int(self._call("getSafetyMode", self._recv.getSafetyMode))
        if mode in STOPPED_SAFETY_MODES or self._call(
            "isProtectiveStopped", self._recv.isProtectiveStopped
        ):
            name = STOPPED_SAFETY_MODES.get(mode, "PROTECTIVE_STOP")
            raise ProtectiveStop(
                f"{self.name}: the controller stopped the arm ({call}): safety mode {mode} "
                f"{name}; find the cause on the teach pendant and unlock the protective stop "
                "before going on"
            )

    # ------------------------------------------------------------------ ArmDriver
    def read(self) -> ArmState:
        """The arm's state: joints, velocities, TCP wrench, gripper position (0..255).

        Raises:
            ConnectionLost: If the RTDE link or the gripper socket dropped.
            StaleState: If the controller timestamp stopped advancing.
            ProtectiveStop: If the controller stopped the arm.
            GripperFault: If the gripper reports a fault.
        """
        self._require()
        self._check_running("read")
        timestamp = float(self._call("getTimestamp", self._recv.getTimestamp))
        self._stale.check(timestamp)
        q = np.asarray(self._call("getActualQ", self._recv.getActualQ), dtype=np.float64)
        qd = np.asarray(self._call("getActualQd", self._recv.getActualQd), dtype=np.float64)
        wrench = np.asarray(
            self._call("getActualTCPForce", self._recv.getActualTCPForce), dtype=np.float64
        )
        assert self._gripper is not None
        self._gripper.check_fault()
        gripper = float(self._gripper.position())
        return ArmState(timestamp, q, qd, gripper, wrench)

    def command_joints(self, joint_pos: np.ndarray, duration: float) -> None:
        """One ``servoJ`` to ``joint_pos`` over ``duration`` s, inside one control period.

        Args:
            joint_pos: Six joint positions (rad).
            duration: Seconds the move takes (> 0).

        Raises:
            ValueError: On a wrong shape or a non-positive or non-finite duration.
            ConnectionLost: If the link dropped.
            ProtectiveStop: If the controller stopped the arm.
            DriverError: If ``servoJ`` returned False for another reason.
        """
        q = [float(v) for v in np.asarray(joint_pos, dtype=np.float64).reshape(-1)]
        if len(q) != NUM_JOINTS:
            raise ValueError(f"{self.name}: {len(q)} joint positions, expected {NUM_JOINTS}")
        if not (math.isfinite(duration) and duration > 0):
            raise ValueError(f"{self.name}: duration must be finite and > 0, got {duration}")
        self._require()
        try:
            start = self._ctrl.initPeriod()
            ok = self._call(
                "servoJ",
                self._ctrl.servoJ,
                q,
                SERVO_SPEED,
                SERVO_ACCEL,
                float(duration),
                SERVO_LOOKAHEAD,
                SERVO_GAIN,
            )
            self._ctrl.waitPeriod(start)
        except KeyboardInterrupt:
            self.stop()
            raise
        if not ok:
            self._check_running("servoJ")
            raise DriverError(
                f"{self.name}: servoJ returned False (the controller refused the command)"
            )

    def command_gripper(self, value: float) -> None:
        """Move the gripper to ``value`` (0 open .. 255 closed) with RMB's speed and force.

        Args:
            value: The gripper command.

        Raises:
            ValueError: If ``value`` is not finite or rounds outside 0..255.
            ConnectionLost: If the gripper socket dropped.
            GripperFault: If the gripper refuses the move.
        """
        self._require()
        if not math.isfinite(value) or not 0 <= round(value) <= 255:
            raise ValueError(f"{self.name}: gripper command {value} outside 0..255")
        assert self._gripper is not None
        self._gripper.move(round(value), self.config.gripper_speed, self.config.gripper_force)

    def zero_wrench(self) -> None:
        """``zeroFtSensor()``.

        Raises:
            DriverError: If it returns False (a :class:`ProtectiveStop` when the arm is
                stopped, :class:`ConnectionLost` when the link dropped).
        """
        self._require()
        if not self._call("zeroFtSensor", self._ctrl.zeroFtSensor):
            self._check_running("zeroFtSensor")
            raise DriverError(f"{self.name}: zeroFtSensor returned False")

    def stop(self) -> None:
        """``servoStop`` then ``stopJ``: the arm decelerates to rest. Never raises: a stop
        that cannot reach the controller is logged (the controller stops a program whose RTDE
        client is gone)."""
        if self._ctrl is None:
            return
        for name, call in (
            ("servoStop", lambda: self._ctrl.servoStop()),
            ("stopJ", lambda: self._ctrl.stopJ(STOP_DECELERATION)),
        ):
            try:
                call()
            except Exception as error:
                log.warning("%s: %s failed while stopping: %s", self.name, name, error)

    def close(self) -> None:
        """Stop the arm, close the gripper socket and both RTDE interfaces (and the twin the
        driver started); safe to call at any time, also twice."""
        self.stop()
        for interface in (self._ctrl, self._recv):
            if interface is not None:
                try:
                    interface.disconnect()
                except Exception as error:
                    log.warning("%s: disconnect failed: %s", self.name, error)
        self._ctrl = self._recv = None
        if self._gripper is not None:
            self._gripper.close()
            self._gripper = None
        if self._own_twin and self._twin is not None:
            self._twin.close()
            self._twin, self._own_twin = None, False
