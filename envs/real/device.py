"""A real robot as one device: its arms (each behind its safety layer) and its cameras.

:class:`RealRobot` is the device class of the one hardware stack
(driver or twin -> :class:`~rmb_lerobot.envs.real.safety.SafetyLayer` -> device -> a LeRobot
``Robot`` plugin and the real backend of :class:`~rmb_lerobot.envs.base.RmbEnv`). It speaks
RMB's vectors: a joint vector is, per arm, its joints (rad) then its gripper (command units,
0..255), the record's :attr:`~rmb_lerobot.envs.robots.Robot.layout`. Every command goes
through each arm's layer (there is no other way to the arm), and anything that goes wrong in
a command, a read or a wait stops every arm before the exception leaves.

:func:`make_real_robot` builds one from a robot name, the driver choice (``"sim"``: the
MuJoCo twins on loopback; ``"sdk"``: the arms at the given addresses) and LeRobot camera
configs.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Iterator, Mapping, Sequence
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from rmb_lerobot.envs.real.cameras import (
    CameraFrame,
    TwinCamera,
    TwinCameraConfig,
    camera_fovy,
    read_frame,
)
from rmb_lerobot.envs.real.driver import ArmState
from rmb_lerobot.envs.real.limits import CONTROL_PERIOD, limits_for
from rmb_lerobot.envs.real.safety import SafetyLayer, SentCommand
from rmb_lerobot.envs.robots import Robot, robot_for

if TYPE_CHECKING:
    from lerobot.cameras import Camera, CameraConfig

__all__ = [
    "REAL_ROBOTS",
    "CameraFrame",
    "RealRobot",
    "RobotState",
    "make_real_robot",
]

log = logging.getLogger(__name__)

REAL_ROBOTS: tuple[str, ...] = ("ur5e", "xarm7", "ur5e_dual")
"""Robot records :func:`make_real_robot` builds."""

_WAIT_SLICE_S = 0.05  # a reset wait sleeps in slices (Ctrl-C is seen within one)


@dataclass(frozen=True)
class RobotState:
    """One reading of every arm, in RMB's vectors.

    Attributes:
        arms: Each arm's checked reading, in arm order.
        joints: RMB's measured joint vector (per arm: joints, then the measured gripper).
        velocities: Joint velocities in the same layout, 0 for each gripper (RMB records
            none).
        wrench: Per arm ``(fx, fy, fz, tx, ty, tz)`` (N, N m); zeros where an arm has no
            sensor.
        time: ``time.monotonic()`` when the reading was complete.
    """

    arms: tuple[ArmState, ...]
    joints: np.ndarray
    velocities: np.ndarray
    wrench: np.ndarray
    time: float


class RealRobot:
    """The arms of one robot record, each behind its safety layer, with its cameras.

    A context manager: ``with`` connects, leaving it (also by an exception or Ctrl-C) stops
    every arm and disconnects.

    Args:
        robot: The robot record (:mod:`rmb_lerobot.envs.robots`); one layer per arm.
        layers: One safety layer per arm, in the record's arm order.
        cameras: LeRobot cameras by RMB camera name (``front``, ``hand``, ...); twin cameras
            are attached to their arm's twin when the robot connects.
        fovy: Vertical field of view (degrees) of cameras that have no intrinsics (OpenCV).

    Raises:
        ValueError: The layers do not match the record's arms.
    """

    def __init__(
        self,
        robot: Robot,
        layers: Sequence[SafetyLayer],
        cameras: Mapping[str, Camera] | None = None,
        *,
        fovy: Mapping[str, float] | None = None,
    ):
        if len(layers) != len(robot.arms):
            raise ValueError(
                f"{robot.name} has {len(robot.arms)} arm(s), got {len(layers)} safety layer(s)"
            )
        for arm, layer in zip(robot.arms, layers, strict=True):
            if layer.limits.num_joints != len(arm.joints):
                raise ValueError(
                    f"{robot.name} arm {arm.name!r} has {len(arm.joints)} joints, its layer "
                    f"limits {layer.limits.num_joints}"
                )
        self.robot = robot
        self.layers = tuple(layers)
        self.cameras: dict[str, Camera] = dict(cameras or {})
        self._fovy_given = dict(fovy or {})
        self.fovy: dict[str, float] = {}
        self._slices = robot.joint_slices()
        self._connected = False
        self.last_state: RobotState | None = None
        self.last_move_duration = 0.0

    # ------------------------------------------------------------------ lifecycle
    @property
    def is_connected(self) -> bool:
        """Whether :meth:`connect` succeeded and :meth:`disconnect` has not run since."""
        return self._connected

    @property
    def num_joints(self) -> int:
        """Length of RMB's joint vector."""
        return self.robot.layout.num_joints

    @property
    def twins(self) -> tuple[Any, ...]:
        """Per arm the twin its driver talks to (``driver: sim``; ``None`` for an SDK)."""
        return tuple(getattr(layer.driver, "twin", None) for layer in self.layers)

    def connect(self) -> None:
        """Connect every arm (taking a first checked reading), then every camera.

        Raises:
            DriverError: An arm did not come up (every arm is closed again).
            SafetyError: A first reading was refused (every arm is closed again).
            ConnectionError: A camera did not come up (everything is closed again).
        """
        if self._connected:
            return
        try:
            for layer in self.layers:
                layer.connect()
            for name, camera in self.cameras.items():
                self._attach_twin(name, camera)
                if not camera.is_connected:
                    camera.connect()
                self.fovy[name] = camera_fovy(camera, self._fovy_given.get(name))
        except BaseException:
            self._close_all()
            raise
        self._connected = True
        self.read()

    def _attach_twin(self, name: str, camera: Camera) -> None:
        if not isinstance(camera, TwinCamera) or camera.attached:
            return
        arm = camera.config.arm
        twins = self.twins
        if not 0 <= arm < len(twins) or twins[arm] is None:
            raise ValueError(
                f"camera {name!r} renders the twin of arm {arm}, but that arm has no twin "
                "(twin cameras need driver 'sim')"
            )
        camera.attach(twins[arm].sim)

    def disconnect(self) -> None:
        """Stop every arm, close the layers (and their drivers) and the cameras; safe to call
        at any time, also twice."""
        self._close_all()
        self._connected = False

    def _close_all(self) -> None:
        for camera in self.cameras.values():
            try:
                if camera.is_connected:
                    camera.disconnect()
            except Exception as error:
                log.warning("%s: camera disconnect failed: %s", self.robot.name, error)
        for layer in self.layers:
            try:
                layer.close()  # stops the arm first
            except Exception as error:
                log.warning("%s: closing %s failed: %s", self.robot.name, layer.limits.robot, error)

    def __enter__(self) -> RealRobot:
        self.connect()
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.disconnect()

    # ------------------------------------------------------------------ state
    def read(self) -> RobotState:
        """One checked reading of every arm (one driver read per arm).

        Returns:
            The state in RMB's vectors (also kept in :attr:`last_state`).

        Raises:
            DriverError: An arm failed (every arm is stopped).
            SafetyError: A reading was refused: stale or not finite (every arm is stopped).
        """
        with self._stopping_all():
            arms = tuple(layer.read() for layer in self.layers)
        joints, velocities, wrenches = [], [], []
        for state in arms:
            joints += [*np.asarray(state.joint_pos, np.float64), float(state.gripper)]
            velocities += [*np.asarray(state.joint_vel, np.float64), 0.0]
            wrench = np.zeros(6) if state.wrench is None else np.asarray(state.wrench, float)
            wrenches += list(wrench)
        self.last_state = RobotState(
            arms=arms,
            joints=np.asarray(joints, dtype=np.float64),
            velocities=np.asarray(velocities, dtype=np.float64),
            wrench=np.asarray(wrenches, dtype=np.float64),
            time=time.monotonic(),
        )
        return self.last_state

    def read_joints(self) -> np.ndarray:
        """RMB's measured joint vector (per arm: joints in rad, then the measured gripper)."""
        return self.read().joints

    def read_velocities(self) -> np.ndarray:
        """Joint velocities (rad/s) in the joint vector's layout, 0 for each gripper."""
        return self.read().velocities

    def read_wrench(self) -> np.ndarray:
        """Per arm the wrist wrench ``(fx, fy, fz, tx, ty, tz)``: 6 numbers per arm."""
        return self.read().wrench

    def read_cameras(self, max_age_ms: int = 500) -> dict[str, CameraFrame]:
        """The newest frame of every camera (no waiting for a new one).

        Args:
            max_age_ms: Refuse a frame older than this (a stalled camera).

        Returns:
            Frames by camera name: RGB, depth in metres (or ``None``), fovy.

        Raises:
            TimeoutError: A camera's newest frame is too old.
        """
        return {
            name: read_frame(camera, self.fovy.get(name, 0.0), max_age_ms)
            for name, camera in self.cameras.items()
        }

    # ------------------------------------------------------------------ commands
    def send(self, command: np.ndarray, duration: float = CONTROL_PERIOD) -> np.ndarray:
        """One control step of every arm (RMB's ``step``) through its safety layer.

        Args:
            command: RMB's command joint vector (per arm: joint targets, gripper).
            duration: Time the arms are given (s): the control period.

        Returns:
            The joint vector actually sent (clamped by the layers).

        Raises:
            ValueError: ``command`` has the wrong length.
            SafetyError: A layer refused the command (nothing was sent to that arm; every arm
                is stopped).
            DriverError: An arm failed (every arm is stopped).
        """
        parts = self._split(command)
        with self._stopping_all():
            sent = [
                layer.step(q, gripper, duration)
                for layer, (q, gripper) in zip(self.layers, parts, strict=True)
            ]
        return self._joined(sent)

    def move_to(
        self, command: np.ndarray, scale: float | None = None, *, wait: bool = True
    ) -> np.ndarray:
        """A reset move of every arm (RMB's reset): each layer chooses its duration from the
        distance and RMB's reset scale (UR5e 0.3, xArm7 0.1 of ``v_lim``).

        Args:
            command: RMB's joint vector to go to.
            scale: ``v_lim`` scale; ``None``: each robot's reset scale.
            wait: Wait until the longest arm's duration has passed (Ctrl-C while waiting
                stops every arm).

        Returns:
            The joint vector sent (the longest duration is in :attr:`last_move_duration`).

        Raises:
            ValueError: ``command`` has the wrong length.
            SafetyError: A layer refused the move (every arm is stopped).
            DriverError: An arm failed (every arm is stopped).
        """
        parts = self._split(command)
        with self._stopping_all():
            sent = [
                layer.move_to(q, gripper, scale)
                for layer, (q, gripper) in zip(self.layers, parts, strict=True)
            ]
            self.last_move_duration = max(s.duration for s in sent)
            if wait:
                deadline = time.monotonic() + self.last_move_duration
                while (left := deadline - time.monotonic()) > 0:
                    time.sleep(min(left, _WAIT_SLICE_S))
        return self._joined(sent)

    def zero_wrench(self) -> None:
        """Zero every arm's force/torque sensor (RMB: after each reset, arms at rest)."""
        with self._stopping_all():
            for layer in self.layers:
                layer.zero_wrench()

    def stop(self) -> None:
        """Stop every arm now (also disarms the watchdogs); never raises for one arm's
        failure before trying the others."""
        errors = []
        for layer in self.layers:
            try:
                layer.stop()
            except Exception as error:
                errors.append(error)
                log.warning(
                    "%s: stopping %s failed: %s", self.robot.name, layer.limits.robot, error
                )
        if errors:
            raise errors[0]

    @contextmanager
    def streaming(self) -> Iterator[RealRobot]:
        """Arm every layer's watchdog for a block of streamed commands (an episode).

        Yields:
            This robot.
        """
        with ExitStack() as stack:
            for layer in self.layers:
                stack.enter_context(layer.streaming())
            yield self

    # ------------------------------------------------------------------ plumbing
    def _split(self, command: np.ndarray) -> list[tuple[np.ndarray, float]]:
        vector = np.asarray(command, dtype=np.float64).reshape(-1)
        if vector.shape != (self.num_joints,):
            raise ValueError(
                f"{self.robot.name}: command has {vector.size} values, expected "
                f"{self.num_joints} (per arm: joints, gripper)"
            )
        return [(vector[arm], float(vector[grip])) for arm, grip in self._slices]

    def _joined(self, sent: Sequence[SentCommand]) -> np.ndarray:
        out = np.empty(self.num_joints, dtype=np.float64)
        for (arm, grip), s in zip(self._slices, sent, strict=True):
            out[arm] = s.joint_pos
            out[grip] = np.nan if s.gripper is None else s.gripper
        return out

    @contextmanager
    def _stopping_all(self) -> Iterator[None]:
        """On any exception (Ctrl-C included), stop every arm, then let it propagate.

        The failing arm's layer has stopped that arm already; the others are stopped here so
        that a dual robot never keeps one arm moving alone.
        """
        try:
            yield
        except BaseException as exc:
            for layer in self.layers:
                try:
                    layer.stop()
                except Exception as stop_exc:
                    exc.add_note(f"stopping {layer.limits.robot} failed too: {stop_exc!r}")
            raise


def make_real_robot(
    robot_name: str,
    *,
    driver: str = "sim",
    hosts: Sequence[str] = ("127.0.0.1",),
    cameras: Mapping[str, CameraConfig] | None = None,
    fovy: Mapping[str, float] | None = None,
    **limits_options: Any,
) -> RealRobot:
    """A real robot by name, its arms behind safety layers, its cameras made by LeRobot.

    Nothing connects here: call :meth:`RealRobot.connect` (or use ``with``).

    Args:
        robot_name: ``"ur5e"``, ``"xarm7"`` or ``"ur5e_dual"`` (two UR5e: left, right).
        driver: ``"sim"`` (each arm's MuJoCo twin, loopback addresses only) or ``"sdk"`` (the
            vendor SDK; the extra ``ur5e`` or ``xarm7``).
        hosts: Each arm's controller address, in arm order (RMB's ``robot_ip``, or
            ``robot_ip_left`` and ``robot_ip_right``). With ``"sim"`` one loopback address
            serves every arm; with ``"sdk"`` write one per arm: there is no default address.
        cameras: LeRobot camera configs by RMB camera name: ``RealSenseCameraConfig(serial,
            use_depth=True)``, ``OpenCVCameraConfig``, or ``TwinCameraConfig`` (``sim`` only).
        fovy: fovy (degrees) of cameras without intrinsics.
        **limits_options: Passed to :func:`~rmb_lerobot.envs.real.limits.limits_for` for every
            arm (``workspace``, ``gripper``, ``watchdog_timeout``).

    Returns:
        The robot, not connected.

    Raises:
        ValueError: An unknown robot or driver, or the wrong number of addresses.
    """
    if robot_name not in REAL_ROBOTS:
        raise ValueError(f"no real robot {robot_name!r}; known: {', '.join(REAL_ROBOTS)}")
    record = robot_for(robot_name)
    hosts = tuple(hosts)
    n = len(record.arms)
    if driver == "sim" and len(hosts) == 1:
        hosts = hosts * n
    if len(hosts) != n:
        raise ValueError(
            f"{robot_name} has {n} arm(s): give {n} address(es) in arm order "
            f"({', '.join(a.name for a in record.arms)}), got {list(hosts)}"
        )
    layers = [
        SafetyLayer(
            _make_driver(robot_name, driver, host), limits_for(robot_name, arm=i, **limits_options)
        )
        for i, host in enumerate(hosts)
    ]
    return RealRobot(record, layers, _make_cameras(cameras or {}), fovy=fovy)


def _make_driver(robot_name: str, driver: str, host: str) -> Any:
    if robot_name == "xarm7":
        from rmb_lerobot.envs.real.drivers.xarm7 import XArm7Config, XArm7Driver

        return XArm7Driver(XArm7Config(host=host, driver=driver))  # type: ignore[arg-type]
    from rmb_lerobot.envs.real.drivers.ur5e import UR5eConfig, UR5eDriver

    return UR5eDriver(UR5eConfig(host=host, driver=driver))  # type: ignore[arg-type]


def _make_cameras(configs: Mapping[str, CameraConfig]) -> dict[str, Camera]:
    """LeRobot's cameras for ``configs`` (the twin's made here, the rest by LeRobot)."""
    twins = {name: TwinCamera(c) for name, c in configs.items() if isinstance(c, TwinCameraConfig)}
    others = {name: c for name, c in configs.items() if name not in twins}
    made: dict[str, Camera] = {}
    if others:
        from lerobot.cameras import make_cameras_from_configs

        made = make_cameras_from_configs(dict(others))
    return {name: twins.get(name) or made[name] for name in configs}
