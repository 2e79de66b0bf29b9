"""LeRobot ``Robot`` plugins for the real arms: ``rmb_ur5e``, ``rmb_xarm7``, ``rmb_ur5e_dual``.

Each single-arm plugin holds one :class:`~rmb_lerobot.envs.real.device.RealRobot` (driver or
twin -> safety layer -> device) and nothing else touches the arm: an action is RMB's command
vector sent through :meth:`RealRobot.send`, so every command passes the safety layer, and
:meth:`RmbArmRobot.send_action` returns what the layer actually sent (LeRobot's contract; the
layer's velocity clamp plays the part of LeRobot's ``max_relative_target``). A non-finite
action, a jump of more than 90° in one step or a stale reading is refused with the layer's
exception, after the arm has been stopped. The dual UR5e is two single-arm plugins, composed
as LeRobot's ``bi_so_follower`` is, and stops both arms when either fails.

Two action spaces (``--robot.action_space``): ``joint`` (default), where an action is the
joint targets and the gripper command, and ``ee_velocity``, where it is an end-effector twist
and the gripper command that the robot integrates into its own end-effector target (started at
the measured pose), solves by IK and sends as joints through the same safety layer
(:mod:`.ee_action`): what a Cartesian teleoperator needs, since LeRobot's stock loops give a
teleoperator no robot state. In ``joint`` mode the first action of a stream is reached by a
duration-scaled reset move when it is far from where the arm stands
(``ramp_first_action``), so a teleoperator or a replayed episode may start anywhere.

Keys (:mod:`.features`): ``<joint>.pos`` per arm joint and ``gripper.pos`` (0 open .. 255
closed), the same in observation and (``joint``) action; each camera ``<name>`` as
``(H, W, 3)`` uint8 RGB, and ``<name>_depth`` as ``(H, W, 1)`` uint16 millimetres where the camera
streams depth (LeRobot's RealSense convention). The wrist wrench, joint velocities and fovy are
not observations here: ``lerobot-rollout`` feeds a policy only ``.pos`` / ``.vel`` floats and
cameras, so any other float in the recorded ``observation.state`` would not match what it feeds
at deployment. RMB's own real envs record those keys.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
from lerobot.robots.robot import Robot
from lerobot.utils.errors import DeviceAlreadyConnectedError, DeviceNotConnectedError

from rmb_lerobot.envs.real.errors import NonFiniteCommand, WatchdogTripped
from rmb_lerobot.envs.real.lerobot_devices.config import (
    EE_VELOCITY_ACTIONS,
    ROBOT_TYPES,
    RmbArmConfig,
    RmbUR5eConfig,
    RmbUR5eDualConfig,
    RmbXarm7Config,
)
from rmb_lerobot.envs.real.lerobot_devices.features import (
    DUAL_SIDES,
    EE_VELOCITY_KEYS,
    GRIPPER_KEY,
    arm_action_keys,
    arm_keys,
)
from rmb_lerobot.envs.robots import robot_for

if TYPE_CHECKING:
    from lerobot.cameras import CameraConfig

    from rmb_lerobot.envs.real.device import RealRobot
    from rmb_lerobot.envs.real.lerobot_devices.ee_action import EeTarget

log = logging.getLogger(__name__)

DEPTH_SUFFIX = "_depth"
_WAIT_SLICE_S = 0.05  # a ramp wait sleeps in slices (Ctrl-C is seen within one)
_MM_PER_M = 1000.0
_UINT16_MAX = 65535


def camera_features(cameras: Mapping[str, CameraConfig]) -> dict[str, tuple[int, int, int]]:
    """Observation features of cameras: ``(H, W, 3)`` RGB, ``(H, W, 1)`` depth if streamed.

    Args:
        cameras: Camera configs by name (width and height set).

    Returns:
        ``{name: (H, W, 3), name + "_depth": (H, W, 1), ...}``.
    """
    features: dict[str, tuple[int, int, int]] = {}
    for name, config in cameras.items():
        features[name] = (int(config.height), int(config.width), 3)
        if getattr(config, "use_depth", False):
            features[name + DEPTH_SUFFIX] = (int(config.height), int(config.width), 1)
    return features


@dataclass(frozen=True)
class ParsedAction:
    """One arm's action, checked and read out of LeRobot's dict.

    Attributes:
        command: Joint action: RMB's command vector (joints, then the gripper); ``None`` for
            an end-effector action.
        twist: End-effector action: ``(vx, vy, vz, ωroll, ωpitch, ωyaw)``; ``None`` for a
            joint action.
        gripper: The gripper command.
    """

    command: np.ndarray | None
    twist: np.ndarray | None
    gripper: float


def wait_s(seconds: float) -> None:
    """Sleep ``seconds`` in short slices (Ctrl-C lands within one).

    Args:
        seconds: How long; nothing happens for 0 or less.
    """
    deadline = time.monotonic() + seconds
    while (left := deadline - time.monotonic()) > 0:
        time.sleep(min(left, _WAIT_SLICE_S))


def depth_to_mm(depth_m: np.ndarray) -> np.ndarray:
    """Depth in metres ``(H, W)`` -> ``(H, W, 1)`` uint16 millimetres, 0 where there is no
    reading (a RealSense's convention): non-finite, negative or beyond 65.535 m (a twin's
    background at the far clipping plane).

    Args:
        depth_m: Depth in metres.

    Returns:
        The depth as LeRobot's RealSense camera returns it.
    """
    mm = np.rint(np.asarray(depth_m, dtype=np.float64) * _MM_PER_M)
    valid = np.isfinite(mm) & (mm >= 0) & (mm <= _UINT16_MAX)
    out = np.where(valid, mm, 0.0).astype(np.uint16)
    return out.reshape(*out.shape[:2], 1)


class RmbArmRobot(Robot):
    """One real arm with its gripper and cameras, as a LeRobot ``Robot``.

    Subclasses name the robot record (:attr:`robot_name`). Building it connects nothing
    (``lerobot-record`` reads the features first); :meth:`connect` brings up the arm (or
    starts its twin) and the cameras.

    Args:
        config: Driver, address, cameras, command duration, watchdog timeout, action space.

    Attributes:
        real: The device every command goes through.
        cameras: The LeRobot cameras by name (``lerobot-record`` needs this attribute).
        ee_target: The end-effector target (``ee_velocity``; built on :meth:`connect`).
        last_sent_joints: The joint vector the last action actually sent (both spaces).
    """

    robot_name: ClassVar[str]

    def __init__(self, config: RmbArmConfig):
        super().__init__(config)  # type: ignore[arg-type]
        from rmb_lerobot.envs.real.device import make_real_robot

        self.config = config
        self.record = robot_for(self.robot_name)
        self.real: RealRobot = make_real_robot(
            self.robot_name,
            driver=config.driver,
            hosts=(config.resolved_host(self.name),),
            cameras=config.cameras,
            watchdog_timeout=config.watchdog_timeout_s,
        )
        self.cameras = self.real.cameras
        self._keys = arm_keys(self.record)
        self._action_keys = arm_action_keys(self.record, config.action_space)
        self._ee_mode = config.action_space == EE_VELOCITY_ACTIONS
        self.ee_target: EeTarget | None = None
        self.last_sent_joints: np.ndarray | None = None
        self._streaming = False

    def __str__(self) -> str:
        return self.name if self.id is None else f"{self.name} {self.id}"

    # ------------------------------------------------------------------ features
    @cached_property
    def action_features(self) -> dict[str, type]:
        """``joint``: ``<joint>.pos`` per arm joint, then ``gripper.pos``; ``ee_velocity``:
        ``ee_x.vel`` .. ``ee_yaw.vel``, then ``gripper.pos``. All ``float``."""
        return dict.fromkeys(self._action_keys, float)

    @cached_property
    def observation_features(self) -> dict[str, type | tuple[int, int, int]]:
        """Measured joints and gripper (``<joint>.pos``, ``gripper.pos``), then the cameras."""
        return {**dict.fromkeys(self._keys, float), **camera_features(self.config.cameras)}

    # ------------------------------------------------------------------ lifecycle
    @property
    def is_connected(self) -> bool:
        """Whether the arm and its cameras are connected."""
        return self.real.is_connected

    @property
    def is_calibrated(self) -> bool:
        """Always: the arms' encoders are absolute, there is nothing to calibrate."""
        return True

    def connect(self, calibrate: bool = True) -> None:
        """Connect the arm (or start its twin) and the cameras; take a first checked reading.

        Args:
            calibrate: Ignored (nothing to calibrate).

        Raises:
            DeviceAlreadyConnectedError: Already connected.
            DriverError: The arm did not come up.
            SafetyError: The first reading was refused.
        """
        if self.is_connected:
            raise DeviceAlreadyConnectedError(f"{self} is already connected")
        if self._ee_mode and self.ee_target is None:
            from rmb_lerobot.envs.real.lerobot_devices.ee_action import (
                EeTarget,
                build_arm_kinematics,
            )

            self.ee_target = EeTarget(build_arm_kinematics(self.record), str(self))
        self.real.connect()
        self._streaming = False
        host = self.config.resolved_host(self.name)
        log.info("%s connected (driver %s at %s)", self, self.config.driver, host)
        self._log_tcp("starts")

    def calibrate(self) -> None:
        """Nothing to calibrate."""

    def configure(self) -> None:
        """Nothing to configure: the drivers set their control modes on connect."""

    def disconnect(self) -> None:
        """Stop the arm, then close it and the cameras.

        Raises:
            DeviceNotConnectedError: Not connected.
        """
        if not self.is_connected:
            raise DeviceNotConnectedError(f"{self} is not connected")
        try:
            self._log_tcp("ends")
        except Exception as error:  # a failed reading must not keep the arm connected
            log.warning("%s: no final reading: %s", self, error)
        self.real.disconnect()
        self._streaming = False

    def _log_tcp(self, when: str) -> None:
        """Log where the end effector stands (``ee_velocity``: the operator's reference)."""
        if self.ee_target is None:
            return
        pose = self.ee_target.kinematics.fk(self.real.read_joints()[:-1])
        log.info(
            "%s: end effector %s at %s m (base frame)", self, when, np.round(pose[:3], 4).tolist()
        )

    def pause_stream(self) -> None:
        """A planned pause in the command stream: disarm the watchdog; the next action
        starts a new stream (:meth:`start_stream`)."""
        for layer in self.real.layers:
            layer.disarm_watchdog()
        self._streaming = False

    @property
    def streaming(self) -> bool:
        """Whether a command stream is running (the next action is not the first)."""
        return self._streaming

    def stop(self) -> None:
        """Stop the arm now (the dual robot stops the other arm with this when one fails)."""
        self.real.stop()
        self._streaming = False

    # ------------------------------------------------------------------ I/O
    def get_observation(self) -> dict[str, Any]:
        """Measured joints and gripper, and the newest frame of every camera.

        Returns:
            ``{<joint>.pos: float, gripper.pos: float, <cam>: (H, W, 3) uint8,
            <cam>_depth: (H, W, 1) uint16 mm}``.

        Raises:
            DeviceNotConnectedError: Not connected.
            SafetyError: The reading was stale or not finite (the arm is stopped).
            TimeoutError: A camera's newest frame is too old.
        """
        if not self.is_connected:
            raise DeviceNotConnectedError(f"{self} is not connected")
        joints = self.real.read_joints()
        obs: dict[str, Any] = {k: float(v) for k, v in zip(self._keys, joints, strict=True)}
        for name, frame in self.real.read_cameras().items():
            obs[name] = frame.rgb
            if name + DEPTH_SUFFIX in self.observation_features:
                if frame.depth is None:
                    raise RuntimeError(f"{self}: camera {name!r} streams no depth this frame")
                obs[name + DEPTH_SUFFIX] = depth_to_mm(frame.depth)
        return obs

    def parse_action(self, action: Mapping[str, Any]) -> ParsedAction:
        """Read one action out of LeRobot's dict, without sending anything.

        An action with every joint key is a joint action in either action space
        (``lerobot-rollout`` returns the arm to its start with the observation's ``.pos``
        keys); otherwise, in ``ee_velocity`` mode, the twist keys and ``gripper.pos``.

        Args:
            action: The action (extra keys are ignored; tensors and numpy scalars work).

        Returns:
            The parsed action.

        Raises:
            KeyError: A key is missing (the message lists what is expected).
        """
        if all(key in action for key in self._keys):
            command = np.array([float(action[key]) for key in self._keys], dtype=np.float64)
            return ParsedAction(command, None, float(command[-1]))
        missing = [key for key in self._action_keys if key not in action]
        if missing or not self._ee_mode:
            raise KeyError(
                f"{self}: action lacks {missing or [k for k in self._keys if k not in action]} "
                f"(expected {list(self._action_keys)})"
            )
        twist = np.array([float(action[key]) for key in EE_VELOCITY_KEYS], dtype=np.float64)
        return ParsedAction(None, twist, float(action[GRIPPER_KEY]))

    def start_stream(self, parsed: ParsedAction) -> float:
        """Begin a command stream: arm the watchdog and, for a joint action far from the
        measured joints, start the safety layer's reset move to it (``ramp_first_action``).

        "Far" is further than a reset move covers in one ``command_duration_s``: anything
        nearer is sent as a step. An end-effector target is re-synced to the measured pose.

        Args:
            parsed: The stream's first action.

        Returns:
            Seconds the reset move takes (0: none started); wait that long before the step.

        Raises:
            SafetyError: The layer refused the reset move (the arm is stopped).
        """
        layer = self.real.layers[0]
        layer.arm_watchdog()
        self._streaming = True
        if self.ee_target is not None:
            self.ee_target.reset()
        if parsed.command is None or not self.config.ramp_first_action:
            return 0.0
        measured = self.real.read_joints()
        limits = layer.limits
        reach = limits.scaled_v_lim(limits.reset_scale) * self.config.command_duration_s
        gap = float(np.max(np.abs(parsed.command[:-1] - measured[:-1])))
        if not gap > reach:
            return 0.0
        self.real.move_to(parsed.command, wait=False)
        duration = self.real.last_move_duration
        log.warning(
            "%s: first action is %.1f° from the measured joints; moving there at reset speed "
            "for %.2f s before streaming",
            self,
            np.rad2deg(gap),
            duration,
        )
        return duration

    def send_action(self, action: Mapping[str, Any]) -> dict[str, float]:
        """Send one action through the safety layer.

        The first action of a stream arms the layer's watchdog (the arm is stopped when
        actions stop coming) and may start with a reset move (:meth:`start_stream`); an
        action after a stop by the watchdog (a pause in LeRobot's loop while it saves an
        episode) starts a new stream from where the arm stands, with a warning.

        Args:
            action: Every key of :attr:`action_features` (extra keys are ignored), or, in
                either action space, every joint key (a joint action). Joint targets (rad),
                twist (m/s, rad/s), gripper command (0..255); tensors and numpy scalars work.

        Returns:
            What was actually sent, in the action's keys: the joint targets and gripper as
            clamped by the layer; for a twist, the twist the sent joints realise (the target's
            change over ``command_duration_s``) and the gripper sent. The joint vector sent
            is in :attr:`last_sent_joints`.

        Raises:
            DeviceNotConnectedError: Not connected.
            KeyError: An action key is missing (nothing is sent).
            SafetyError: The layer refused the action: ``NonFiniteCommand`` (NaN/inf),
                ``JumpTooLarge``, ``OutsideWorkspace``, a stale or non-finite reading; nothing
                was sent and the arm is stopped.
            DriverError: The arm failed (it is stopped).
        """
        if not self.is_connected:
            raise DeviceNotConnectedError(f"{self} is not connected")
        parsed = self.parse_action(action)
        if not self._streaming:
            with self._stopping_on_interrupt():
                wait_s(self.start_stream(parsed))
        try:
            return self._send(parsed)
        except WatchdogTripped as tripped:
            log.warning("%s: %s; resuming from where the arm stands", self, tripped)
            for layer in self.real.layers:
                if layer.watchdog.tripped:
                    layer.resume()
            with self._stopping_on_interrupt():
                wait_s(self.start_stream(parsed))
            return self._send(parsed)

    @contextmanager
    def _stopping_on_interrupt(self) -> Iterator[None]:
        try:
            yield
        except BaseException:
            self.stop()
            raise

    def _send(self, parsed: ParsedAction) -> dict[str, float]:
        duration = self.config.command_duration_s
        if parsed.command is not None:
            if self.ee_target is not None:
                self.ee_target.reset()  # the next twist starts from the measured pose again
            sent = self.real.send(parsed.command, duration)
            self.last_sent_joints = sent
            return {key: float(v) for key, v in zip(self._keys, sent, strict=True)}
        assert self.ee_target is not None and parsed.twist is not None
        measured = self.real.read_joints()
        if self.ee_target.pose is None:
            self.ee_target.sync(measured[:-1])
        before = self.ee_target.pose.copy()
        bad = [k for k, v in zip(EE_VELOCITY_KEYS, parsed.twist, strict=True) if not np.isfinite(v)]
        if bad:  # refused before the IK, as the layer refuses a non-finite joint command
            self.stop()
            raise NonFiniteCommand(f"{self}: action {bad} not finite: {parsed.twist.tolist()}")
        step = self.ee_target.step(parsed.twist, duration, measured[:-1])
        if step.resynced:
            before = self.ee_target.kinematics.fk(measured[:-1])
        sent = self.real.send(np.append(step.joint_pos, parsed.gripper), duration)
        clipped = not np.allclose(sent[:-1], step.joint_pos, rtol=0.0, atol=1e-9)
        self.ee_target.sent(sent[:-1], clipped)
        self.last_sent_joints = sent
        from rmb_lerobot.envs.real.lerobot_devices.ee_action import pose_twist

        realised = pose_twist(before, self.ee_target.pose, duration)
        out = {key: float(v) for key, v in zip(EE_VELOCITY_KEYS, realised, strict=True)}
        out[GRIPPER_KEY] = float(sent[-1])
        return out


class RmbUR5e(RmbArmRobot):
    """A UR5e with a Robotiq 2F-85 (``--robot.type=rmb_ur5e``)."""

    config_class = RmbUR5eConfig
    name = "rmb_ur5e"
    robot_name = ROBOT_TYPES["rmb_ur5e"]


class RmbXarm7(RmbArmRobot):
    """An xArm7 with its gripper (``--robot.type=rmb_xarm7``)."""

    config_class = RmbXarm7Config
    name = "rmb_xarm7"
    robot_name = ROBOT_TYPES["rmb_xarm7"]


class RmbUR5eDual(Robot):
    """Two UR5e arms (``--robot.type=rmb_ur5e_dual``), composed as LeRobot's bimanual robots.

    ``left_arm`` and ``right_arm`` are :class:`RmbUR5e` plugins; every key of an arm is
    prefixed ``left_`` / ``right_`` (``left_shoulder_pan_joint.pos``, ``right_gripper.pos``,
    ``left_hand``); cell cameras (``config.cameras``) keep their names and are opened by the
    left arm. Whatever fails in one arm (a refusal, a driver error, Ctrl-C) stops the other
    arm too before the exception leaves, so one arm never moves on alone.

    Args:
        config: The two arms and the cell cameras.
    """

    config_class = RmbUR5eDualConfig
    name = "rmb_ur5e_dual"

    def __init__(self, config: RmbUR5eDualConfig):
        super().__init__(config)
        self.config = config
        self._cell_cameras = set(config.cameras)
        arm_configs = {"left": config.left_arm_config, "right": config.right_arm_config}
        arms: dict[str, RmbUR5e] = {}
        for side in DUAL_SIDES:
            arm = arm_configs[side]
            cameras = {**arm.cameras, **config.cameras} if side == "left" else dict(arm.cameras)
            arms[side] = RmbUR5e(
                RmbUR5eConfig(
                    id=f"{config.id}_{side}" if config.id else None,
                    calibration_dir=config.calibration_dir,
                    driver=arm.driver,
                    host=arm.host,
                    cameras=cameras,
                    command_duration_s=arm.command_duration_s,
                    watchdog_timeout_s=arm.watchdog_timeout_s,
                    action_space=arm.action_space,
                    ramp_first_action=arm.ramp_first_action,
                )
            )
        self.left_arm, self.right_arm = arms["left"], arms["right"]
        self.cameras = {self._prefixed("left", k): v for k, v in self.left_arm.cameras.items()} | {
            self._prefixed("right", k): v for k, v in self.right_arm.cameras.items()
        }

    def __str__(self) -> str:
        return self.name if self.id is None else f"{self.name} {self.id}"

    def _prefixed(self, side: str, key: str) -> str:
        return key if side == "left" and key in self._cell_cameras else f"{side}_{key}"

    def _arms(self) -> tuple[tuple[str, RmbUR5e], ...]:
        return (("left", self.left_arm), ("right", self.right_arm))

    # ------------------------------------------------------------------ features
    @cached_property
    def action_features(self) -> dict[str, type]:
        """Both arms' action keys, prefixed, left first."""
        return {
            f"{side}_{key}": ft
            for side, arm in self._arms()
            for key, ft in arm.action_features.items()
        }

    @cached_property
    def observation_features(self) -> dict[str, type | tuple[int, int, int]]:
        """Both arms' joints (prefixed), then the cameras (arm cameras prefixed)."""
        joints = dict(self.action_features)
        cameras = {
            self._prefixed(side, key): ft
            for side, arm in self._arms()
            for key, ft in arm.observation_features.items()
            if isinstance(ft, tuple)
        }
        return {**joints, **cameras}

    # ------------------------------------------------------------------ lifecycle
    @property
    def is_connected(self) -> bool:
        """Whether both arms are connected."""
        return self.left_arm.is_connected and self.right_arm.is_connected

    @property
    def is_calibrated(self) -> bool:
        """Always: nothing to calibrate."""
        return True

    def connect(self, calibrate: bool = True) -> None:
        """Connect the left arm, then the right (the left is closed again if the right fails).

        Args:
            calibrate: Ignored (nothing to calibrate).

        Raises:
            DeviceAlreadyConnectedError: Already connected.
        """
        if self.is_connected:
            raise DeviceAlreadyConnectedError(f"{self} is already connected")
        try:
            for _, arm in self._arms():
                if not arm.is_connected:
                    arm.connect(calibrate)
        except BaseException:
            for _, arm in self._arms():
                if arm.is_connected:
                    arm.disconnect()
            raise

    def calibrate(self) -> None:
        """Nothing to calibrate."""

    def configure(self) -> None:
        """Nothing to configure."""

    def disconnect(self) -> None:
        """Stop and close both arms (each is tried even if the other fails)."""
        errors = []
        for _, arm in self._arms():
            try:
                if arm.is_connected:
                    arm.disconnect()
            except Exception as error:
                errors.append(error)
        if errors:
            raise errors[0]

    @contextmanager
    def _stopping_both(self, side: str) -> Iterator[None]:
        try:
            yield
        except BaseException as exc:
            exc.add_note(f"in the {side} arm of {self.name}; both arms were stopped")
            for other_side, arm in self._arms():
                if arm.is_connected:
                    try:
                        arm.stop()
                    except Exception as stop_exc:
                        exc.add_note(f"stopping the {other_side} arm failed too: {stop_exc!r}")
            raise

    # ------------------------------------------------------------------ I/O
    def get_observation(self) -> dict[str, Any]:
        """Both arms' observations, keys prefixed (cell cameras as they are).

        Returns:
            The observation, keys as :attr:`observation_features`.
        """
        obs: dict[str, Any] = {}
        for side, arm in self._arms():
            with self._stopping_both(side):
                part = arm.get_observation()
            obs |= {self._prefixed(side, key): value for key, value in part.items()}
        return obs

    def send_action(self, action: Mapping[str, Any]) -> dict[str, float]:
        """Split the action by prefix and send each arm its part through its safety layer.

        Both arms' parts are checked first, so a missing key sends nothing. Where a stream
        starts with a reset move (``ramp_first_action``), both arms' moves run together and
        the step follows when the longer one is done.

        Args:
            action: Every key of :attr:`action_features` (or every joint key of both arms).

        Returns:
            What was actually sent, keys prefixed.

        Raises:
            KeyError: An action key is missing (nothing is sent).
        """
        parts: dict[str, dict[str, Any]] = {}
        parsed: dict[str, ParsedAction] = {}
        for side, arm in self._arms():
            prefix = f"{side}_"
            parts[side] = {
                k.removeprefix(prefix): v for k, v in action.items() if k.startswith(prefix)
            }
            try:
                parsed[side] = arm.parse_action(parts[side])
            except KeyError as missing:
                raise KeyError(f"{self}: {side} arm: {missing.args[0]}") from None
        ramps = [0.0]
        for side, arm in self._arms():
            if arm.is_connected and not arm.streaming:
                with self._stopping_both(side):
                    ramps.append(arm.start_stream(parsed[side]))
                if ramps[-1] == 0.0:
                    # Nothing to reach: start its stream with its first step, after the wait,
                    # or its watchdog would stop it while the other arm moves.
                    arm.pause_stream()
        with self._stopping_both("either"):
            wait_s(max(ramps))
        sent: dict[str, float] = {}
        for side, arm in self._arms():
            with self._stopping_both(side):
                result = arm.send_action(parts[side])
            sent |= {f"{side}_{key}": value for key, value in result.items()}
        return sent
