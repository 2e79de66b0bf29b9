"""A simulated xArm7 controller answering xarm-python-sdk's ``XArmAPI`` calls, on MuJoCo.

:class:`XArm7Twin` is the controller (one MuJoCo xArm7 with its gripper in wall-clock time,
see :class:`~rmb_lerobot.envs.real.twins.sim.ArmSim`); :meth:`XArm7Twin.XArmAPI` builds an
object with ``xarm.wrapper.XArmAPI``'s call signatures (xarm-python-sdk 1.18) for the subset a
driver uses, returning the SDK's codes: 0 success, -1 not connected, -8 a joint target out of
range (the SDK's own check), 1 the controller has an error (``error_code`` then says which:
22 self-collision, 23 joint limit, 31 collision), 3 no reply in time, 9 not ready (state 4),
102 gripper fault. As in the SDK, getters return 0 while the controller has an error: the
error shows in ``error_code`` and ``state``.

Fault hooks for tests: :meth:`XArm7Twin.drop_connection`, :meth:`XArm7Twin.fail_next` (a call
returns a code), :meth:`XArm7Twin.protective_stop`, :meth:`XArm7Twin.gripper_fault`,
:meth:`XArm7Twin.freeze` (the controller stops answering: code 3, as the SDK reports a reply
timeout). The twin stops the arm by itself on a joint limit (error 23) or a collision (31).

What the twin does not model: the controller's trajectory planner (the target moves linearly
over ``max(mvtime, max|dq| / speed)``), its acceleration limits, collision sensitivity levels,
and the gripper's speed.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Sequence
from typing import Any

import numpy as np

from rmb_lerobot.envs.real.drivers.common import is_loopback
from rmb_lerobot.envs.real.drivers.gripper_units import (
    xarm_gripper_command_to_pulse,
    xarm_gripper_pulse_to_command,
)
from rmb_lerobot.envs.real.twins.sim import ArmSim, Box
from rmb_lerobot.envs.robots import XARM7

# xarm-python-sdk's return codes (xarm/x3/code.py APIState, xarm/core/config/x_config.py).
NOT_CONNECTED, OUT_OF_RANGE = -1, -8
HAS_ERROR, RES_TIMEOUT, STATE_NOT_READY = 1, 3, 9
END_EFFECTOR_HAS_FAULT = 102
# Controller error codes the twin raises by itself.
ERROR_JOINT_LIMIT, ERROR_COLLISION = 23, 31
# Controller states: 1 moving, 2 idle (ready), 4 stopped.
STATE_MOVING, STATE_IDLE, STATE_STOPPED = 1, 2, 4


class XArm7Twin:
    """The simulated xArm7 controller with its gripper and fault hooks.

    Args:
        host: The loopback address the twin answers at.
        obstacles: Fixed boxes in the arm's world (collisions stop the arm, error 31).
    """

    def __init__(self, host: str = "127.0.0.1", *, obstacles: Sequence[Box] = ()):
        if not is_loopback(host):
            raise ValueError(f"the xArm7 twin only runs on loopback, not {host!r}")
        self.host = host
        self._lock = threading.Lock()
        self.error_code = 0
        self.enabled = False
        self.mode = 0
        self.state = STATE_STOPPED
        self.gripper_error = 0
        self.gripper_enabled = False
        self._link_up = True
        self._frozen = False
        self._fail: dict[str, int] = {}
        self._ft_offset = np.zeros(6)
        self.sim = ArmSim(XARM7, obstacles=obstacles, on_stop=self._stopped)

    def XArmAPI(
        self,
        port: str | None = None,
        is_radian: bool = False,
        do_not_open: bool = False,
        **kwargs: Any,
    ) -> XArmAPITwin:
        """``xarm.wrapper.XArmAPI(port, is_radian, do_not_open)`` answered by this twin."""
        return XArmAPITwin(self, port, is_radian=is_radian, do_not_open=do_not_open)

    # ------------------------------------------------------------------ controller state
    def _stopped(self, reason: str) -> None:
        with self._lock:
            if self.error_code == 0:
                self.error_code = (
                    ERROR_COLLISION if reason.startswith("collision") else ERROR_JOINT_LIMIT
                )
            self.state = STATE_STOPPED

    def reachable(self, host: str | None) -> bool:
        """Whether a client for ``host`` can reach this controller now."""
        return self._link_up and host is not None and (host == self.host or is_loopback(host))

    def answer(self, call: str, connected: bool) -> int:
        """The code a call gets before it does anything: 0 to go on.

        Args:
            call: The SDK method's name.
            connected: Whether the client is connected.
        """
        if not connected or not self._link_up:
            return NOT_CONNECTED
        if self._frozen:
            return RES_TIMEOUT
        with self._lock:
            return self._fail.pop(call, 0)

    def ready(self) -> bool:
        """Enabled, no error, not stopped."""
        return self.enabled and self.error_code == 0 and self.state != STATE_STOPPED

    def current_state(self) -> int:
        """``state``: 4 stopped, 1 moving, 2 idle."""
        if self.state == STATE_STOPPED:
            return STATE_STOPPED
        return STATE_IDLE if self.sim.at_rest() else STATE_MOVING

    def zero_ft(self) -> None:
        """The current wrench becomes the zero."""
        self._ft_offset = self.sim.read().wrench

    def wrench(self) -> list[float]:
        """The zeroed wrist wrench ``[fx, fy, fz, tx, ty, tz]``."""
        return [float(v) for v in self.sim.read().wrench - self._ft_offset]

    # ------------------------------------------------------------------ fault hooks
    def drop_connection(self) -> None:
        """The network goes down: every call returns -1 and ``connected`` turns False; the
        controller stops the arm."""
        self._link_up = False
        self.sim.hold()

    def fail_next(self, call: str, code: int) -> None:
        """Make the next ``call`` (an SDK method name) return ``code``."""
        with self._lock:
            self._fail[call] = code

    def protective_stop(
        self, reason: str = "collision injected by a test", code: int = ERROR_COLLISION
    ) -> None:
        """Stop the arm with controller error ``code`` (default 31, collision)."""
        with self._lock:
            self.error_code = code
        self.sim.protective_stop(reason)

    def gripper_fault(self, code: int = 8) -> None:
        """The gripper reports error ``code``; its moves are refused (SDK code 102)."""
        self.gripper_error = code
        self.sim.set_gripper(self.sim.read().gripper)

    def freeze(self, frozen: bool = True) -> None:
        """The controller stops (or resumes) answering: calls return 3 (reply timeout)."""
        self._frozen = frozen

    def reset(self) -> None:
        """Power-on state: no error, not enabled, connected, arm at home (tests)."""
        with self._lock:
            self.error_code = self.gripper_error = 0
            self.enabled = self.gripper_enabled = False
            self.mode, self.state = 0, STATE_STOPPED
            self._link_up, self._frozen = True, False
            self._fail.clear()
        self._ft_offset = np.zeros(6)
        self.sim.reset()

    def close(self) -> None:
        """Stop the arm and the simulation; safe to call twice."""
        self.sim.close()


class XArmAPITwin:
    """``xarm.wrapper.XArmAPI`` answered by an :class:`XArm7Twin` (the subset drivers use)."""

    def __init__(
        self, twin: XArm7Twin, port: str | None, is_radian: bool = False, do_not_open: bool = False
    ):
        self._twin = twin
        self._port = port
        self._default_is_radian = is_radian
        self._connected = False
        if not do_not_open:
            self.connect()

    # ------------------------------------------------------------------ connection
    def connect(self, port: str | None = None, *args: Any, **kwargs: Any) -> None:
        """Connect (raises ``Exception`` as the SDK does when nothing answers)."""
        if port is not None:
            self._port = port
        if not self._twin.reachable(self._port):
            raise Exception(f"can not connect to port/ip {self._port}")
        self._connected = True

    def disconnect(self) -> None:
        self._connected = False

    @property
    def connected(self) -> bool:
        return self._connected and self._twin._link_up

    @property
    def error_code(self) -> int:
        return self._twin.error_code

    @property
    def warn_code(self) -> int:
        return 0

    @property
    def has_err_warn(self) -> bool:
        return self._twin.error_code != 0

    @property
    def state(self) -> int:
        return self._twin.current_state()

    @property
    def mode(self) -> int:
        return self._twin.mode

    def _gate(self, call: str) -> int:
        return self._twin.answer(call, self._connected)

    # ------------------------------------------------------------------ setup calls
    def motion_enable(self, enable: bool = True, servo_id: int | None = None) -> int:
        code = self._gate("motion_enable")
        if code == 0:
            self._twin.enabled = bool(enable)
            if not enable:
                self._twin.state = STATE_STOPPED
                self._twin.sim.hold()
        return code

    def set_ft_sensor_enable(self, on_off: int) -> int:
        return self._gate("set_ft_sensor_enable")

    def set_ft_sensor_zero(self) -> int:
        code = self._gate("set_ft_sensor_zero")
        if code == 0:
            self._twin.zero_ft()
        return code

    ft_sensor_enable = set_ft_sensor_enable  # the SDK's aliases
    ft_sensor_set_zero = set_ft_sensor_zero

    def clean_error(self) -> int:
        code = self._gate("clean_error")
        if code == 0:
            with self._twin._lock:
                self._twin.error_code = 0
            self._twin.sim.clear_stop()
        return code

    def set_mode(self, mode: int = 0, detection_param: int = 0) -> int:
        code = self._gate("set_mode")
        if code == 0:
            self._twin.mode = int(mode)
        return code

    def set_state(self, state: int = 0) -> int:
        code = self._gate("set_state")
        if code != 0:
            return code
        if state == 0:
            if self._twin.error_code == 0 and self._twin.enabled:
                self._twin.state = STATE_IDLE
        elif state in (3, 4, 6):
            self._twin.state = STATE_STOPPED
            self._twin.sim.hold()
        return code

    def set_collision_sensitivity(self, value: int, wait: bool = True) -> int:
        return self._gate("set_collision_sensitivity")

    def clean_gripper_error(self, **kwargs: Any) -> int:
        code = self._gate("clean_gripper_error")
        if code == 0:
            self._twin.gripper_error = 0
        return code

    def set_gripper_mode(self, mode: int, **kwargs: Any) -> int:
        return self._gate("set_gripper_mode")

    def set_gripper_enable(self, enable: bool, **kwargs: Any) -> int:
        code = self._gate("set_gripper_enable")
        if code == 0:
            self._twin.gripper_enabled = bool(enable)
        return code

    def emergency_stop(self) -> None:
        if self._gate("emergency_stop") == 0:
            self._twin.sim.hold()
            self._twin.state = STATE_IDLE if self._twin.enabled else STATE_STOPPED

    # ------------------------------------------------------------------ commands
    def set_servo_angle(
        self,
        servo_id: int | None = None,
        angle: Sequence[float] | None = None,
        speed: float | None = None,
        mvacc: float | None = None,
        mvtime: float | None = None,
        relative: bool = False,
        is_radian: bool | None = None,
        wait: bool = False,
        timeout: float | None = None,
        radius: float | None = None,
        **kwargs: Any,
    ) -> int:
        """Move all seven joints (``servo_id`` None) to ``angle``, as in mode 6."""
        code = self._gate("set_servo_angle")
        if code != 0:
            return code
        if self._twin.error_code != 0:
            return HAS_ERROR
        if not self._twin.ready():
            return STATE_NOT_READY
        if servo_id not in (None, 8) or angle is None or len(angle) != 7 or relative:
            return -3  # API_EXCEPTION: the twin takes absolute moves of all joints
        radian = self._default_is_radian if is_radian is None else is_radian
        goal = np.asarray(angle, dtype=np.float64) * (1.0 if radian else math.pi / 180.0)
        low, high = self._twin.sim.joint_range.T
        if np.any(goal < low - math.radians(0.1)) or np.any(goal > high + math.radians(0.1)):
            return OUT_OF_RANGE
        reading = self._twin.sim.read()
        duration = float(mvtime or 0.0)
        if speed:
            rate = float(speed) * (1.0 if radian else math.pi / 180.0)
            duration = max(duration, float(np.max(np.abs(goal - reading.target))) / rate)
        return 0 if self._twin.sim.move_to(goal, duration) else HAS_ERROR

    def set_gripper_position(
        self,
        pos: float,
        wait: bool = False,
        speed: float | None = None,
        auto_enable: bool = False,
        timeout: float | None = None,
        **kwargs: Any,
    ) -> int:
        code = self._gate("set_gripper_position")
        if code != 0:
            return code
        if self._twin.gripper_error != 0:
            return END_EFFECTOR_HAS_FAULT
        if self._twin.gripper_enabled or auto_enable:
            self._twin.sim.set_gripper(xarm_gripper_pulse_to_command(float(pos)))
        return 0

    # ------------------------------------------------------------------ readings
    def get_joint_states(self, is_radian: bool | None = None, num: int = 3) -> tuple[int, list]:
        code = self._gate("get_joint_states")
        reading = self._twin.sim.read()
        scale = (
            1.0 if (self._default_is_radian if is_radian is None else is_radian) else 180 / math.pi
        )
        result = [list(reading.joint_pos * scale), list(reading.joint_vel * scale), [0.0] * 7]
        return code, result[: max(1, min(num, 3))]

    def get_gripper_position(self, **kwargs: Any) -> tuple[int, float | None]:
        code = self._gate("get_gripper_position")
        pulse = xarm_gripper_command_to_pulse(self._twin.sim.read().gripper)
        return code, (pulse if code == 0 else None)

    def get_gripper_err_code(self, **kwargs: Any) -> tuple[int, int]:
        return self._gate("get_gripper_err_code"), self._twin.gripper_error

    def get_ft_sensor_data(self, is_raw: bool = False) -> tuple[int, list[float]]:
        code = self._gate("get_ft_sensor_data")
        return code, (self._twin.wrench() if code == 0 else [0.0] * 6)

    def get_state(self) -> tuple[int, int]:
        return self._gate("get_state"), self._twin.current_state()

    def get_err_warn_code(self, show: bool = False, lang: str = "en") -> tuple[int, list[int]]:
        return self._gate("get_err_warn_code"), [self._twin.error_code, 0]
