"""xArm7 driver with xarm-python-sdk's ``XArmAPI``: RMB's calls, every return code checked.

The calls are RMB's (``RealXarm7EnvBase``): ``XArmAPI(ip)``, ``connect()``,
``motion_enable(True)``, ``ft_sensor_enable(1)``, ``ft_sensor_set_zero()``, ``clean_error()``,
``set_mode(6)`` (online joint trajectory), ``set_state(0)``, ``set_collision_sensitivity(1)``,
``clean_gripper_error()``, ``set_gripper_mode(0)``, ``set_gripper_enable(True)`` (with RMB's
0.2 s pauses); a joint command is ``set_servo_angle(angle=q, speed=..., mvtime=duration,
is_radian=True, wait=False)``, the gripper ``set_gripper_position(pulse, wait=False)``;
readings are ``get_joint_states(is_radian=True)``, ``get_gripper_position()`` and
``get_ft_sensor_data()``.

Every non-zero return code raises an :class:`~rmb_lerobot.envs.real.driver.SdkError` naming
the call and the code; where the code says more it is also the matching subclass
(:class:`XArmConnectionLost`, :class:`XArmStale`, :class:`XArmProtectiveStop`,
:class:`XArmGripperFault`), so ``except SdkError`` and ``except ProtectiveStop`` both work.

The gripper is commanded in the record's units (0 open .. 255 closed) and converted to the
SDK's pulses in :mod:`rmb_lerobot.envs.real.drivers.gripper_units`.

The xArm SDK has no controller timestamp: every reading is a request answered by the
controller, so :attr:`~rmb_lerobot.envs.real.driver.ArmState.timestamp` is this computer's
monotonic clock when the answer came, and a controller that stops answering shows as the SDK's
code 3 (reply timeout), raised as :class:`XArmStale`.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from rmb_lerobot.envs.real.driver import (
    ArmState,
    ConnectionLost,
    GripperFault,
    ProtectiveStop,
    SdkError,
    StaleState,
)
from rmb_lerobot.envs.real.drivers.common import DriverKind, check_driver_config, import_sdk
from rmb_lerobot.envs.real.drivers.gripper_units import (
    xarm_gripper_command_to_pulse,
    xarm_gripper_pulse_to_command,
)

if TYPE_CHECKING:
    from rmb_lerobot.envs.real.twins.xarm7 import XArm7Twin

log = logging.getLogger(__name__)

NUM_JOINTS = 7
MODE_ONLINE_JOINT_TRAJECTORY = 6
STATE_READY, STATE_STOP = 0, 4

# xarm-python-sdk's API codes (xarm/x3/code.py) and what they mean.
API_CODES: dict[int, str] = {
    -1: "not connected",
    -2: "not ready (motion not enabled or state not set)",
    -3: "API exception (bad arguments)",
    -7: "joint angle limit",
    -8: "out of range (a joint target outside its limits)",
    -9: "emergency stop",
    1: "the controller has an uncleared error",
    2: "the controller has an uncleared warning",
    3: "no reply from the controller in time",
    4: "reply length error",
    5: "reply sequence error",
    6: "protocol error",
    7: "reply does not match the command",
    8: "send error",
    9: "state not ready (the arm is stopped: set_state(0))",
    10: "result invalid or execution failed",
    11: "other error",
    12: "parameter error",
    102: "end effector (gripper) fault",
}
# Controller error codes (``XArmAPI.error_code``) that stop the arm, by name.
CONTROLLER_ERRORS: dict[int, str] = {
    1: "emergency stop button pressed",
    2: "emergency IO triggered",
    3: "three-state switch emergency stop",
    22: "self-collision",
    23: "joint angle exceeds limit",
    24: "speed exceeds limit",
    31: "collision caused abnormal current",
    35: "safety boundary limit",
    38: "abnormal joint angle",
}
_CONNECTION_CODES = (-1, 8)
_STALE_CODES = (3,)
_STOP_CODES = (-9, 1, 9)
_GRIPPER_CODES = (102,)


class XArmConnectionLost(SdkError, ConnectionLost):
    """An SDK call returned a code meaning the connection is gone (-1, 8)."""


class XArmStale(SdkError, StaleState):
    """An SDK call returned 3: the controller did not answer in time."""


class XArmProtectiveStop(SdkError, ProtectiveStop):
    """The controller has an error and stopped the arm (``code``: the API or error code)."""


class XArmGripperFault(SdkError, GripperFault):
    """The gripper reported an error (``code``: the SDK's 102 or the gripper's error code)."""


@dataclass
class XArm7Config:
    """How to reach one xArm7 with its gripper.

    Attributes:
        host: The xArm controller's address (no default: write your arm's address; ``sim``
            needs a loopback address such as ``127.0.0.1``).
        driver: ``"sdk"`` drives the arm with xarm-python-sdk; ``"sim"`` drives the MuJoCo
            twin.
        joint_speed: ``speed`` (rad/s) of every ``set_servo_angle``: the planner's cap, so a
            move can finish in its duration (RMB: 2.0 x v_lim = 360 deg/s per step; the
            safety layer is what bounds each step).
        collision_sensitivity: ``set_collision_sensitivity`` (RMB: 1).
        settle_s: RMB's pauses after enabling the F/T sensor, zeroing it and enabling the
            gripper.
    """

    host: str
    driver: DriverKind = "sim"
    joint_speed: float = math.radians(360.0)
    collision_sensitivity: int = 1
    settle_s: float = 0.2


class XArm7Driver:
    """One xArm7 with its gripper (:class:`~rmb_lerobot.envs.real.driver.ArmDriver`).

    A context manager: leaving the ``with`` block (also by an exception or Ctrl-C) stops the
    arm and disconnects.

    Args:
        config: Where the arm is and which driver talks to it.
        twin: With ``driver: sim``, the twin to talk to (default: the driver starts its own
            and closes it in :meth:`close`).
    """

    def __init__(self, config: XArm7Config, twin: XArm7Twin | None = None):
        check_driver_config("xArm7", config.driver, config.host)
        if twin is not None and config.driver != "sim":
            raise ValueError("XArm7Driver: a twin is only used with driver 'sim'")
        self.config = config
        self.name = f"xArm7 at {config.host}"
        self._twin = twin
        self._own_twin = False
        self._arm: Any = None
        self._halted = False

    @property
    def twin(self) -> XArm7Twin | None:
        """The twin this driver talks to (``driver: sim``), else ``None``."""
        return self._twin

    # ------------------------------------------------------------------ codes
    def _error(self, call: str, code: int) -> SdkError:
        """The exception for a non-zero ``code`` returned by ``call``."""
        text = f"{self.name}: {call} returned code {code} ({API_CODES.get(code, 'unknown code')})"
        if code in _CONNECTION_CODES:
            return XArmConnectionLost(text, code)
        if code in _STALE_CODES:
            return XArmStale(f"{text}: stale state", code)
        if code in _GRIPPER_CODES:
            return XArmGripperFault(f"{text}; gripper error {self._gripper_error()}", code)
        controller_error = self._controller_error()
        if code in _STOP_CODES and controller_error:
            return XArmProtectiveStop(f"{text}; {self._describe(controller_error)}", code)
        return SdkError(text, code)

    def _check(self, call: str, result: Any) -> Any:
        """Raise for a non-zero code; return what came with a ``(code, value)`` result."""
        code, value = (result[0], result[1]) if isinstance(result, tuple) else (result, None)
        if code is None:  # a few SDK setters return None on success
            code = 0
        if int(code) != 0:
            raise self._error(call, int(code))
        return value

    def _call(self, call: str, *args: Any, **kwargs: Any) -> Any:
        """Call ``XArmAPI.<call>`` and check its code."""
        if self._arm is None:
            raise ConnectionLost(f"{self.name}: not connected (call connect() first)")
        return self._check(call, getattr(self._arm, call)(*args, **kwargs))

    def _controller_error(self) -> int:
        try:
            return int(self._arm.error_code or 0)
        except Exception:
            return 0

    def _gripper_error(self) -> str:
        try:
            code, error = self._arm.get_gripper_err_code()
            return str(error) if code == 0 else f"unknown (get_gripper_err_code returned {code})"
        except Exception as error:
            return f"unknown ({error})"

    def _describe(self, controller_error: int) -> str:
        what = CONTROLLER_ERRORS.get(controller_error, "see the xArm controller error table")
        return (
            f"controller error {controller_error} ({what}): the arm is stopped; clear the cause, "
            "then clean_error / motion_enable / set_state(0)"
        )

    # ------------------------------------------------------------------ connection
    def connect(self) -> None:
        """RMB's connect sequence: enable, zero the F/T sensor, mode 6, state 0, gripper on.

        Raises:
            ImportError: If ``driver: sdk`` and xarm-python-sdk is not installed (naming the
                extra).
            ConnectionLost: If the controller does not answer.
            SdkError: If any call returns a non-zero code.
        """
        self.close()
        cfg = self.config
        if cfg.driver == "sim":
            if self._twin is None:
                from rmb_lerobot.envs.real.twins.xarm7 import XArm7Twin

                self._twin, self._own_twin = XArm7Twin(cfg.host), True
            make_api = self._twin.XArmAPI
        else:
            make_api = import_sdk("xarm.wrapper", "xarm7").XArmAPI
        try:
            try:
                self._arm = make_api(cfg.host)
                self._arm.connect()
            except Exception as error:  # the SDK raises a bare Exception
                self._arm = None
                raise ConnectionLost(f"{self.name}: cannot connect: {error}") from error
            self._call("motion_enable", True)
            self._call("ft_sensor_enable", 1)
            time.sleep(cfg.settle_s)
            self._call("ft_sensor_set_zero")
            time.sleep(cfg.settle_s)
            self._call("clean_error")
            self._ready()
            self._call("set_collision_sensitivity", cfg.collision_sensitivity)
            self._call("clean_gripper_error")
            self._call("set_gripper_mode", 0)
            self._call("set_gripper_enable", True)
            time.sleep(cfg.settle_s)
            self._call("get_joint_states", is_radian=True)
        except BaseException:
            self.close()
            raise

    def _ready(self) -> None:
        self._call("set_mode", MODE_ONLINE_JOINT_TRAJECTORY)
        self._call("set_state", STATE_READY)
        self._halted = False

    def __enter__(self) -> XArm7Driver:
        self.connect()
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    def _check_running(self) -> None:
        if self._arm is None:
            raise ConnectionLost(f"{self.name}: not connected (call connect() first)")
        if not self._arm.connected:
            raise XArmConnectionLost(f"{self.name}: connection lost ({API_CODES[-1]})", -1)
        controller_error = self._controller_error()
        if controller_error:
            raise XArmProtectiveStop(
                f"{self.name}: {self._describe(controller_error)}", controller_error
            )

    # ------------------------------------------------------------------ ArmDriver
    def read(self) -> ArmState:
        """The arm's state: joints, velocities, F/T wrench, gripper (0 open .. 255 closed).

        Raises:
            ConnectionLost: If the connection dropped.
            StaleState: If the controller stopped answering (code 3).
            ProtectiveStop: If the controller has an error (the arm is stopped).
            SdkError: On any other non-zero code.
        """
        self._check_running()
        positions, velocities = self._call("get_joint_states", is_radian=True)[:2]
        pulse = self._call("get_gripper_position")
        wrench = self._call("get_ft_sensor_data")
        return ArmState(
            timestamp=time.monotonic(),
            joint_pos=np.asarray(positions, dtype=np.float64),
            joint_vel=np.asarray(velocities, dtype=np.float64),
            gripper=float(xarm_gripper_pulse_to_command(float(pulse))),
            wrench=np.asarray(wrench, dtype=np.float64),
        )

    def command_joints(self, joint_pos: np.ndarray, duration: float) -> None:
        """``set_servo_angle(angle=q, speed, mvtime=duration, is_radian=True, wait=False)``.

        After :meth:`stop` the arm is made ready again first (mode 6, state 0).

        Args:
            joint_pos: Seven joint positions (rad).
            duration: Seconds the move takes (> 0).

        Raises:
            ValueError: On a wrong shape or a non-positive or non-finite duration.
            SdkError: On a non-zero code (with its subclass where the code says more).
        """
        q = [float(v) for v in np.asarray(joint_pos, dtype=np.float64).reshape(-1)]
        if len(q) != NUM_JOINTS:
            raise ValueError(f"{self.name}: {len(q)} joint positions, expected {NUM_JOINTS}")
        if not (math.isfinite(duration) and duration > 0):
            raise ValueError(f"{self.name}: duration must be finite and > 0, got {duration}")
        try:
            if self._halted:
                self._ready()
            self._call(
                "set_servo_angle",
                angle=q,
                speed=self.config.joint_speed,
                mvtime=float(duration),
                is_radian=True,
                wait=False,
            )
        except KeyboardInterrupt:
            self.stop()
            raise

    def command_gripper(self, value: float) -> None:
        """``set_gripper_position(pulse, wait=False)`` for a command 0 (open) .. 255 (closed).

        Args:
            value: The gripper command (record units).

        Raises:
            ValueError: If ``value`` is not finite.
            SdkError: On a non-zero code (:class:`XArmGripperFault` for a gripper fault).
        """
        if not math.isfinite(value):
            raise ValueError(f"{self.name}: gripper command {value} is not finite")
        self._call("set_gripper_position", xarm_gripper_command_to_pulse(value), wait=False)

    def zero_wrench(self) -> None:
        """``ft_sensor_set_zero()``.

        Raises:
            SdkError: On a non-zero code.
        """
        self._call("ft_sensor_set_zero")

    def stop(self) -> None:
        """``set_state(4)``: the arm stops. Never raises: a stop that cannot reach the
        controller is logged (the controller stops the arm when its client is gone)."""
        if self._arm is None:
            return
        self._halted = True
        try:
            code = self._arm.set_state(STATE_STOP)
            if code:
                log.warning("%s: set_state(4) returned %s while stopping", self.name, code)
        except Exception as error:
            log.warning("%s: set_state(4) failed while stopping: %s", self.name, error)

    def close(self) -> None:
        """Stop and disconnect (and close the twin the driver started); safe to call at any
        time, also twice."""
        self.stop()
        if self._arm is not None:
            try:
                self._arm.disconnect()
            except Exception as error:
                log.warning("%s: disconnect failed: %s", self.name, error)
            self._arm = None
        if self._own_twin and self._twin is not None:
            self._twin.close()
            self._twin, self._own_twin = None, False
