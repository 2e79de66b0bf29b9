"""One arm of a robot record in MuJoCo, stepped in wall-clock time like the real arm.

:class:`ArmSim` is the physical part every twin shares: the robot's MuJoCo model (the same
one the simulated envs use, :func:`~rmb_lerobot.envs.mujoco.robots.build_robot_model`) on a
floor, with its stand and optional obstacle boxes, stepped by a background thread so that
simulated time follows the wall clock. Commands set position targets that move linearly to the
goal over the commanded duration (the controller's interpolation); gravity is compensated, as
an arm controller does. The simulation stops the arm by itself, as a controller's safety
system does (a *protective stop*), when a joint leaves its range or a moving part of the arm
touches something fixed (floor, stand, obstacle); tests can also stop it on purpose.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import mujoco
import numpy as np

from rmb_lerobot.envs.mujoco.robots import build_robot_model
from rmb_lerobot.envs.real.testing import wait_for
from rmb_lerobot.envs.robots import Robot

log = logging.getLogger(__name__)

_LIMIT_MARGIN = 1e-3  # rad a joint may pass its range by before the arm stops
_MAX_LAG_S = 0.1  # simulated time dropped when the thread falls further behind the wall clock
_MAX_STEPS_PER_LOCK = 25  # steps taken while holding the lock (readers wait at most that)
_IDLE_SLEEP_S = 0.002


@dataclass(frozen=True)
class Box:
    """A fixed box in the twin's world (an obstacle a test can drive the arm into).

    Attributes:
        pos: Centre in the world frame (m).
        half_size: Half sizes (m).
    """

    pos: tuple[float, float, float]
    half_size: tuple[float, float, float]


@dataclass(frozen=True)
class SimReading:
    """One reading of the simulated arm (copies, safe to keep).

    Attributes:
        time: Simulated time (s) since the twin started.
        joint_pos: Arm joint positions (rad).
        joint_vel: Arm joint velocities (rad/s).
        target: The current position target (rad).
        gripper: Measured gripper value in the units of its command (the record's formula).
        gripper_target: The gripper command.
        wrench: Force (N) and torque (N m) at the wrist sensor, in the sensor's frame.
    """

    time: float
    joint_pos: np.ndarray
    joint_vel: np.ndarray
    target: np.ndarray
    gripper: float
    gripper_target: float
    wrench: np.ndarray


class _Motion:
    """A linear move of the position target from ``start`` to ``goal`` over ``[t0, t1]``."""

    def __init__(self, start: np.ndarray, goal: np.ndarray, t0: float, t1: float):
        self.start, self.goal, self.t0, self.t1 = start, goal, t0, max(t1, t0 + 1e-6)

    def at(self, t: float) -> np.ndarray:
        s = min(max((t - self.t0) / (self.t1 - self.t0), 0.0), 1.0)
        return self.start + (self.goal - self.start) * s


class ArmSim:
    """A single-arm robot record in MuJoCo, stepped in wall-clock time by a thread.

    Args:
        robot: A single-arm record (:data:`~rmb_lerobot.envs.robots.UR5E`,
            :data:`~rmb_lerobot.envs.robots.XARM7`).
        obstacles: Fixed boxes added to the world.
        on_stop: Called (from the sim thread or the caller) with the reason whenever the
            arm is protectively stopped; twins turn it into their controller's state.
    """

    def __init__(
        self,
        robot: Robot,
        *,
        obstacles: Sequence[Box] = (),
        on_stop: Callable[[str], None] | None = None,
    ):
        if len(robot.arms) != 1:
            raise ValueError(f"ArmSim drives one arm; {robot.name!r} has {len(robot.arms)}")
        self.robot = robot
        built = build_robot_model(robot)
        self.arm = built.arms[0]
        spec = built.spec
        world = spec.worldbody
        world.add_geom(name="twin_floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[3, 3, 0.1])
        boxes = list(obstacles)
        if built.stand is not None:
            boxes.insert(0, Box(built.stand.pos, built.stand.half_size))
        for i, box in enumerate(boxes):
            world.add_geom(
                name=f"twin_box{i}",
                type=mujoco.mjtGeom.mjGEOM_BOX,
                pos=list(box.pos),
                size=list(box.half_size),
            )
        self.model = spec.compile()
        self.data = mujoco.MjData(self.model)
        self.arm.set_home(self.model, self.data)
        m = self.model
        joints = [m.joint(name) for name in self.arm.arm_joints]
        self._qadr = np.array([j.qposadr[0] for j in joints])
        self._dadr = np.array([j.dofadr[0] for j in joints])
        self._act = np.array([m.actuator(name).id for name in self.arm.arm_actuators])
        self._grip_act = m.actuator(self.arm.gripper_actuator).id
        self.joint_range = np.array([j.range for j in joints], dtype=np.float64)
        self._limited = np.array([bool(m.jnt_limited[j.id]) for j in joints])
        self._force = m.sensor(self.arm.force_sensor)
        self._torque = m.sensor(self.arm.torque_sensor)
        self._on_stop = on_stop
        self._lock = threading.RLock()
        home = self.data.qpos[self._qadr].copy()
        self._motion = _Motion(home, home, 0.0, 0.0)
        self._stop_reason: str | None = None
        self._origin = time.monotonic()
        self._closing = threading.Event()
        self._thread = threading.Thread(target=self._run, name=f"{robot.name}-twin", daemon=True)
        self._thread.start()

    # ------------------------------------------------------------------ thread
    def _run(self) -> None:
        dt = self.model.opt.timestep
        while not self._closing.is_set():
            owed = time.monotonic() - self._origin - self.data.time
            if owed > _MAX_LAG_S:  # the machine stalled us: drop simulated time, not steps
                self._origin += owed - _MAX_LAG_S
                owed = _MAX_LAG_S
            steps = int(owed / dt)
            if steps <= 0:
                time.sleep(_IDLE_SLEEP_S)
                continue
            with self._lock:
                for _ in range(min(steps, _MAX_STEPS_PER_LOCK)):
                    self._step()
                reason = self._safety_violation()
            if reason is not None:
                self.protective_stop(reason)

    def _step(self) -> None:
        d = self.data
        target = self._motion.at(self._origin + d.time)
        d.ctrl[self._act] = target
        d.qfrc_applied[self._dadr] = d.qfrc_bias[self._dadr]  # gravity compensation
        mujoco.mj_step(self.model, d)

    def _safety_violation(self) -> str | None:
        if self._stop_reason is not None:
            return None
        q = self.data.qpos[self._qadr]
        low, high = self.joint_range[:, 0], self.joint_range[:, 1]
        out = self._limited & ((q < low - _LIMIT_MARGIN) | (q > high + _LIMIT_MARGIN))
        if out.any():
            i = int(np.flatnonzero(out)[0])
            return (
                f"joint limit: {self.arm.arm_joints[i]} at {q[i]:.3f} rad, outside "
                f"[{low[i]:.3f}, {high[i]:.3f}]"
            )
        m, d = self.model, self.data
        for contact in d.contact[: d.ncon]:
            bodies = (m.geom_bodyid[contact.geom1], m.geom_bodyid[contact.geom2])
            fixed = [m.body_weldid[b] == 0 for b in bodies]
            if fixed[0] != fixed[1]:
                moving = bodies[1] if fixed[0] else bodies[0]
                other = contact.geom1 if fixed[0] else contact.geom2
                return (
                    f"collision: {m.body(moving).name or f'body {moving}'} hit "
                    f"{m.geom(other).name or f'geom {other}'}"
                )
        return None

    # ------------------------------------------------------------------ commands
    @property
    def stop_reason(self) -> str | None:
        """Why the arm is protectively stopped, or ``None`` when it is not."""
        return self._stop_reason

    def now(self) -> float:
        """The wall-clock time the motion targets are scheduled in (``time.monotonic``)."""
        return time.monotonic()

    def move_to(self, goal: Sequence[float], duration: float) -> bool:
        """Move the target linearly from where it is now to ``goal`` over ``duration`` s.

        Args:
            goal: Arm joint positions (rad).
            duration: Seconds the move takes.

        Returns:
            False (and nothing moves) while the arm is protectively stopped.
        """
        goal = np.asarray(goal, dtype=np.float64).copy()
        if goal.shape != self._qadr.shape:
            raise ValueError(
                f"{self.robot.name}: goal has shape {goal.shape}, expected {self._qadr.shape}"
            )
        with self._lock:
            if self._stop_reason is not None:
                return False
            now = self.now()
            self._motion = _Motion(self._motion.at(now), goal, now, now + max(float(duration), 0.0))
        return True

    def hold(self) -> None:
        """Stop moving: the target becomes the measured position (the arm decelerates)."""
        with self._lock:
            q = self.data.qpos[self._qadr].copy()
            self._motion = _Motion(q, q, 0.0, 0.0)

    def protective_stop(self, reason: str) -> None:
        """Stop the arm as the controller's safety system would, until :meth:`clear_stop`.

        Args:
            reason: What happened (kept in :attr:`stop_reason`).
        """
        with self._lock:
            first = self._stop_reason is None
            if first:
                self._stop_reason = reason
            self.hold()
        if first:
            log.info("%s twin: protective stop: %s", self.robot.name, reason)
            if self._on_stop is not None:
                self._on_stop(reason)

    def clear_stop(self) -> None:
        """Release a protective stop (the arm holds where it is)."""
        with self._lock:
            self.hold()
            self._stop_reason = None

    def reset(self) -> None:
        """Back to the home pose at rest, gripper at its home command, no stop (tests)."""
        with self._lock:
            mujoco.mj_resetData(self.model, self.data)
            self.arm.set_home(self.model, self.data)
            home = self.data.qpos[self._qadr].copy()
            self._motion = _Motion(home, home, 0.0, 0.0)
            self._stop_reason = None
            self._origin = time.monotonic()

    def set_gripper(self, value: float) -> None:
        """Command the gripper actuator (units of its command, clipped to its range).

        Args:
            value: The command.
        """
        low, high = self.arm.gripper_ctrl_range
        with self._lock:
            self.data.ctrl[self._grip_act] = float(np.clip(value, low, high))

    # ------------------------------------------------------------------ readings
    def read(self) -> SimReading:
        """The arm's state now (copies)."""
        d = self.data
        with self._lock:
            return SimReading(
                time=float(d.time),
                joint_pos=d.qpos[self._qadr].copy(),
                joint_vel=d.qvel[self._dadr].copy(),
                target=self._motion.at(self.now()).copy(),
                gripper=self.arm.gripper_value(d),
                gripper_target=float(d.ctrl[self._grip_act]),
                wrench=np.concatenate(
                    [
                        d.sensordata[self._force.adr[0] : self._force.adr[0] + 3],
                        d.sensordata[self._torque.adr[0] : self._torque.adr[0] + 3],
                    ]
                ),
            )

    def copy_state(self, out: mujoco.MjData) -> float:
        """Copy the simulation state into ``out`` (a renderer's own data) under the stepping
        lock, so that a camera never sees a half-stepped state and never holds the lock while
        it renders.

        Args:
            out: Data made from :attr:`model`; its time, positions, velocities and controls
                are overwritten (call ``mujoco.mj_forward`` on it before rendering).

        Returns:
            The simulated time of the copy (s).
        """
        d = self.data
        with self._lock:
            out.time = d.time
            out.qpos[:] = d.qpos
            out.qvel[:] = d.qvel
            out.ctrl[:] = d.ctrl
            return float(d.time)

    def at_rest(self, vel_tol: float = 0.02) -> bool:
        """Whether the arm is still: every joint slower than ``vel_tol`` rad/s and the target
        not moving.

        Args:
            vel_tol: Joint speed (rad/s) below which a joint counts as still.
        """
        reading = self.read()
        with self._lock:
            settled = self.now() >= self._motion.t1
        return settled and bool(np.all(np.abs(reading.joint_vel) < vel_tol))

    def wait(self, done: Callable[[], bool], timeout_s: float, poll_s: float = 0.01) -> bool:
        """Poll ``done`` until it is true or ``timeout_s`` passes (tests and examples).

        Args:
            done: The condition.
            timeout_s: Bound (s).
            poll_s: Polling period (s).

        Returns:
            Whether ``done`` became true.
        """
        return wait_for(done, timeout_s, poll_s)

    def close(self) -> None:
        """Hold the arm and stop the thread; safe to call twice."""
        self.hold()
        self._closing.set()
        if self._thread.is_alive() and threading.current_thread() is not self._thread:
            self._thread.join(timeout=2.0)
