"""A simulated UR5e controller: ur-rtde's interfaces and the Robotiq URCap socket, on MuJoCo.

:class:`UR5eTwin` is the controller (one MuJoCo UR5e + 2F-85 in wall-clock time, see
:class:`~rmb_lerobot.envs.real.twins.sim.ArmSim`, and a Robotiq URCap server on loopback).
:meth:`UR5eTwin.RTDEControlInterface` and :meth:`UR5eTwin.RTDEReceiveInterface` build objects
with the call signatures of ``rtde_control.RTDEControlInterface`` and
``rtde_receive.RTDEReceiveInterface`` (ur-rtde 1.6) for the subset a driver uses, with the
same return conventions (``bool`` for commands, lists for vectors, ``RuntimeError`` when no
controller answers at the address).

Fault hooks for tests: :meth:`UR5eTwin.drop_connection`, :meth:`UR5eTwin.fail_next` (a
command returns ``False``), :meth:`UR5eTwin.protective_stop`, :meth:`UR5eTwin.gripper_fault`,
:meth:`UR5eTwin.freeze_timestamps` (stale state). The twin stops the arm by itself on a joint
limit or a collision (safety mode 3, protective stop), and when its connection drops.

What the twin does not model: servoJ's lookahead and gain (the target moves linearly over
the command's time), the controller's speed and acceleration limits, the TCP-frame wrench
(the twin reports the wrist sensor's frame), and the dashboard server.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Sequence

import numpy as np

from rmb_lerobot.envs.real.drivers.common import is_loopback
from rmb_lerobot.envs.real.twins.robotiq_server import RobotiqServer
from rmb_lerobot.envs.real.twins.sim import ArmSim, Box
from rmb_lerobot.envs.robots import UR5E

# ur-rtde's SafetyMode and RobotMode values (ur_rtde/rtde_receive_interface.h).
SAFETY_NORMAL, SAFETY_PROTECTIVE_STOP = 1, 3
ROBOT_MODE_RUNNING = 7
RTDE_PORT = 30004  # the controller's RTDE port, as ur-rtde names it in its errors


class UR5eTwin:
    """The simulated UR5e controller with its Robotiq gripper and fault hooks.

    Args:
        host: The loopback address the twin answers at (and its gripper server listens on).
        gripper_port: The gripper server's port (0: any free port; read :attr:`gripper_port`).
        obstacles: Fixed boxes in the arm's world (collisions stop the arm).
        frequency: The controller's period is ``1 / frequency`` (RTDE: 500 Hz).
    """

    def __init__(
        self,
        host: str = "127.0.0.1",
        *,
        gripper_port: int = 0,
        obstacles: Sequence[Box] = (),
        frequency: float = 500.0,
    ):
        if not is_loopback(host):
            raise ValueError(f"the UR5e twin only runs on loopback, not {host!r}")
        self.host = host
        self.period = 1.0 / frequency
        self.sim = ArmSim(UR5E, obstacles=obstacles)
        self.gripper = RobotiqServer(self.sim, host, gripper_port)
        self._lock = threading.Lock()
        self._link_up = True
        self._frozen_at: float | None = None
        self._fail: set[str] = set()
        self._ft_offset = np.zeros(6)
        self._t0 = time.monotonic()

    # ------------------------------------------------------------------ the SDK's classes
    def RTDEControlInterface(self, hostname: str, *args, **kwargs) -> RTDEControlTwin:
        """``rtde_control.RTDEControlInterface(hostname, frequency, flags, ur_cap_port,
        rt_priority)`` answered by this twin."""
        return RTDEControlTwin(self, hostname)

    def RTDEReceiveInterface(self, hostname: str, *args, **kwargs) -> RTDEReceiveTwin:
        """``rtde_receive.RTDEReceiveInterface(hostname, frequency, variables, ...)`` answered
        by this twin."""
        return RTDEReceiveTwin(self, hostname)

    @property
    def gripper_port(self) -> int:
        """The port the gripper's URCap server listens on."""
        return self.gripper.port

    # ------------------------------------------------------------------ state
    def reachable(self, hostname: str) -> bool:
        """Whether an interface for ``hostname`` can reach this controller now."""
        return self._link_up and (hostname == self.host or is_loopback(hostname))

    def timestamp(self) -> float:
        """The controller's clock (s since it started), frozen while timestamps are frozen."""
        with self._lock:
            if self._frozen_at is not None:
                return self._frozen_at
        return time.monotonic() - self._t0

    def safety_mode(self) -> int:
        """ur-rtde's safety mode: 1 normal, 3 protective stop."""
        return SAFETY_NORMAL if self.sim.stop_reason is None else SAFETY_PROTECTIVE_STOP

    def take_failure(self, call: str) -> bool:
        """Whether ``call`` was told to fail once by :meth:`fail_next` (and forget it)."""
        with self._lock:
            if call in self._fail:
                self._fail.discard(call)
                return True
            return False

    def zero_ft(self) -> None:
        """Zero the wrench: the current reading becomes the offset."""
        self._ft_offset = self.sim.read().wrench

    def wrench(self) -> list[float]:
        """The zeroed wrist wrench ``[fx, fy, fz, tx, ty, tz]``."""
        return list(self.sim.read().wrench - self._ft_offset)

    # ------------------------------------------------------------------ fault hooks
    def drop_connection(self) -> None:
        """The network to the controller goes down: RTDE interfaces report not connected,
        commands raise, readings freeze, the gripper socket closes; the arm stops (a UR
        program stops when its RTDE client is gone)."""
        self._link_up = False
        self.freeze_timestamps(True)
        self.sim.hold()
        self.gripper.drop_connections()

    def fail_next(self, call: str) -> None:
        """Make the next ``call`` (``"servoJ"``, ``"zeroFtSensor"``, ...) return ``False``."""
        with self._lock:
            self._fail.add(call)

    def protective_stop(self, reason: str = "protective stop injected by a test") -> None:
        """Stop the arm as the safety system does (safety mode 3)."""
        self.sim.protective_stop(reason)

    def unlock_protective_stop(self) -> None:
        """Release a protective stop (the dashboard's ``unlock protective stop``)."""
        self.sim.clear_stop()

    def gripper_fault(self, code: int = 0x0E) -> None:
        """The gripper reports fault ``code`` (default 0x0E, overcurrent)."""
        self.gripper.inject_fault(code)

    def freeze_timestamps(self, frozen: bool = True) -> None:
        """Stop (or restart) the controller clock the receive interface reports."""
        now = self.timestamp()
        with self._lock:
            self._frozen_at = now if frozen else None

    def reset(self) -> None:
        """Clear every fault, reconnect, power the gripper off, put the arm at home (tests)."""
        self.gripper.drop_connections()
        with self._lock:
            self._link_up = True
            self._frozen_at = None
            self._fail.clear()
        self._ft_offset = np.zeros(6)
        self.gripper.reset()
        self.sim.reset()

    def close(self) -> None:
        """Stop the arm, the gripper server and the simulation; safe to call twice."""
        self.gripper.close()
        self.sim.close()


class _Interface:
    """What both interfaces share: the connection to the twin."""

    _what = "RTDE interface"

    def __init__(self, twin: UR5eTwin, hostname: str):
        self._twin = twin
        self._hostname = hostname
        self._open = False
        self.reconnect()

    def reconnect(self) -> bool:
        if not self._twin.reachable(self._hostname):
            raise RuntimeError(f"Could not connect to: {self._hostname} at {RTDE_PORT}")
        self._open = True
        return True

    def isConnected(self) -> bool:
        return self._open and self._twin.reachable(self._hostname)

    def disconnect(self) -> None:
        self._open = False

    def _require(self, call: str) -> None:
        if not self.isConnected():
            raise RuntimeError(f"{self._what}: {call}: not connected to {self._hostname}")


class RTDEControlTwin(_Interface):
    """``rtde_control.RTDEControlInterface`` answered by a :class:`UR5eTwin`."""

    _what = "RTDEControlInterface"

    def servoJ(
        self,
        q: Sequence[float],
        speed: float,
        acceleration: float,
        duration: float,
        lookahead_time: float,
        gain: float,
    ) -> bool:
        """Move the target to ``q`` over ``duration`` s (ur-rtde's positional ``time``);
        False in a protective stop."""
        self._require("servoJ")
        if len(q) != 6:
            raise RuntimeError(f"servoJ: q has {len(q)} values, expected 6")
        if self._twin.take_failure("servoJ"):
            return False
        goal = np.asarray(q, dtype=np.float64)
        low, high = self._twin.sim.joint_range.T
        outside = np.flatnonzero((goal < low) | (goal > high))
        if outside.size and self._twin.sim.stop_reason is None:
            i = int(outside[0])
            self._twin.sim.protective_stop(
                f"joint limit: servoJ target {goal[i]:.3f} rad for "
                f"{UR5E.arms[0].joints[i]} outside [{low[i]:.3f}, {high[i]:.3f}]"
            )
            return False
        return self._twin.sim.move_to(goal, duration)

    def servoStop(self, a: float = 10.0) -> bool:
        self._require("servoStop")
        self._twin.sim.hold()
        return True

    def stopJ(self, a: float = 2.0, asynchronous: bool = False) -> bool:
        self._require("stopJ")
        self._twin.sim.hold()
        return True

    def stopScript(self) -> None:
        self._twin.sim.hold()

    def zeroFtSensor(self) -> bool:
        self._require("zeroFtSensor")
        if self._twin.take_failure("zeroFtSensor"):
            return False
        self._twin.zero_ft()
        return True

    def endFreedriveMode(self) -> bool:
        self._require("endFreedriveMode")
        return True

    def isProgramRunning(self) -> bool:
        return self.isConnected() and self._twin.sim.stop_reason is None

    def isSteady(self) -> bool:
        return self._twin.sim.at_rest()

    def initPeriod(self) -> float:
        """The start of a control period (ur-rtde returns a steady-clock time point)."""
        return time.monotonic()

    def waitPeriod(self, t_cycle_start: float) -> None:
        """Sleep until one controller period after ``t_cycle_start``."""
        left = t_cycle_start + self._twin.period - time.monotonic()
        if left > 0:
            time.sleep(left)


class RTDEReceiveTwin(_Interface):
    """``rtde_receive.RTDEReceiveInterface`` answered by a :class:`UR5eTwin`.

    As ur-rtde's receive interface does, the getters return the last values received: after
    the connection drops they keep returning them (and the timestamp stops advancing), and
    :meth:`isConnected` turns False.
    """

    _what = "RTDEReceiveInterface"

    def __init__(self, twin: UR5eTwin, hostname: str):
        self._last: dict[str, object] = {}
        super().__init__(twin, hostname)

    def _value(self, name: str, fresh):
        if self.isConnected():
            self._last[name] = fresh()
        if name not in self._last:
            raise RuntimeError(f"{self._what}: {name}: nothing received from {self._hostname}")
        return self._last[name]

    def getTimestamp(self) -> float:
        return self._value("timestamp", self._twin.timestamp)

    def getActualQ(self) -> list[float]:
        return self._value("q", lambda: list(self._twin.sim.read().joint_pos))

    def getActualQd(self) -> list[float]:
        return self._value("qd", lambda: list(self._twin.sim.read().joint_vel))

    def getTargetQ(self) -> list[float]:
        return self._value("target_q", lambda: list(self._twin.sim.read().target))

    def getActualTCPForce(self) -> list[float]:
        return self._value("tcp_force", self._twin.wrench)

    def getSafetyMode(self) -> int:
        return self._value("safety_mode", self._twin.safety_mode)

    def getRobotMode(self) -> int:
        return self._value("robot_mode", lambda: ROBOT_MODE_RUNNING)

    def isProtectiveStopped(self) -> bool:
        return self._value(
            "protective_stopped", lambda: self._twin.safety_mode() == SAFETY_PROTECTIVE_STOP
        )

    def isEmergencyStopped(self) -> bool:
        return self._value("emergency_stopped", lambda: False)
