"""The real backend of :class:`~rmb_lerobot.envs.base.RmbEnv`: a real robot, paced in wall-clock
time.

:class:`RealBackend` drives a :class:`~rmb_lerobot.envs.real.device.RealRobot` (each arm behind
its safety layer; on the twins with ``driver: sim``). It has no scene (:attr:`scene` is
``None``: no success test, success is the operator's call), RMB's control period of 0.02 s
(50 Hz, from which the env's frame rate follows), the layers' joint bounds, measured joints,
velocities and wrench, cameras as RGB + depth (m) + fovy, and eef poses from the same MuJoCo
kinematics as the simulated envs (the robot record's model: eef frame in the arm's root frame).

One step is RMB's: send the command (through the layers), wait for the end of the period,
read the arms. The reading at the tick is the observation the next command is computed from;
:attr:`timing` keeps each tick and the latency from that reading to the next command sent.
A reset is RMB's: a reset move at the robot's reset scale, waited for (and, not RMB's, until
the arm has arrived within a tolerance), then the wrench zeroed between two pauses; the
watchdogs are armed from the end of a reset.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from rmb_lerobot.envs.backend import Backend
from rmb_lerobot.envs.real.cameras import read_frame
from rmb_lerobot.envs.real.device import RealRobot, RobotState, make_real_robot
from rmb_lerobot.envs.real.options import RealOptions
from rmb_lerobot.envs.real.realtime import PreviousPolicy, use_realtime_priority

if TYPE_CHECKING:
    from rmb_lerobot.envs.mujoco.kinematics import ArmKinematics
    from rmb_lerobot.envs.robots import Robot
    from rmb_lerobot.envs.tasks.base import Task
    from rmb_lerobot.envs.workspace import Workspace

log = logging.getLogger(__name__)


@dataclass
class LoopTiming:
    """Wall-clock timing of the control loop since the last reset.

    Attributes:
        ticks: ``time.monotonic()`` of each period's end (when the arms are read).
        latencies: Per step, seconds from the reading of the previous tick to the command
            being handed to the arms (policy, env and safety-layer time together).
        overruns: Steps that reached the tick late (the loop resynchronised after them).
    """

    ticks: list[float] = field(default_factory=list)
    latencies: list[float] = field(default_factory=list)
    overruns: int = 0

    def periods(self) -> np.ndarray:
        """Seconds between consecutive ticks."""
        return np.diff(np.asarray(self.ticks, dtype=np.float64))

    def clear(self) -> None:
        """Forget everything (a new episode)."""
        self.ticks.clear()
        self.latencies.clear()
        self.overruns = 0


class RealBackend(Backend):
    """A real robot (or its twins) behind the env core.

    Args:
        task: The task (a neutral demo task: no success test).
        robot: The robot record (``ur5e``, ``xarm7``, ``ur5e_dual``).
        workspace: The task's workspace (unused: a real cell has its own geometry).
        options: How to reach the robot and cameras (:class:`RealOptions`).
        device: A robot to drive instead of making one from ``options`` (not connected yet, or
            connected; closed by :meth:`close`).

    Raises:
        DriverError: An arm did not come up.
        ValueError: A missing address or a bad camera name.
    """

    simulator = "real"

    def __init__(
        self,
        task: Task,
        robot: Robot,
        workspace: Workspace,
        options: RealOptions | None = None,
        *,
        device: RealRobot | None = None,
    ):
        options = options or RealOptions()
        self.task, self.robot, self.workspace, self.options = task, robot, workspace, options
        self.control_dt = float(options.control_dt)
        self.image_size = options.image_size  # type: ignore[assignment]
        extra = {} if options.tcp_box is None else {"workspace": options.tcp_box}
        self.device = device or make_real_robot(
            robot.name,
            driver=options.driver,
            hosts=options.hosts_for(robot),
            cameras=options.camera_configs_for(robot),
            watchdog_timeout=options.watchdog_timeout,
            **extra,
        )
        self.cameras = tuple(self.device.cameras)
        self._kinematics: tuple[ArmKinematics, ...] | None = None
        self._command: np.ndarray | None = None
        self._t0 = time.monotonic()
        self._next_tick = self._t0
        self._obs_time = self._t0
        self.timing = LoopTiming()
        self.last_sent: np.ndarray | None = None
        self._previous_policy: PreviousPolicy | None = None
        self.device.connect()
        assert self.device.last_state is not None
        self._state: RobotState = self.device.last_state

    # ---------------------------------------------------------------- episode
    def reset(self, world_offset: np.ndarray, home: np.ndarray) -> None:
        """RMB's reset: move to ``home`` at the reset scale and wait, zero the wrench between
        two pauses, then arm the watchdogs (``world_offset`` is ignored: no scene)."""
        self._disarm()
        if self.options.realtime_priority is not None and self._previous_policy is None:
            self._previous_policy = use_realtime_priority(self.options.realtime_priority)
        self.device.move_to(home, scale=self.options.reset_scale)
        self._settle(np.asarray(home, dtype=np.float64))
        time.sleep(self.options.settle_s)
        self.device.zero_wrench()
        time.sleep(self.options.settle_s)
        self._command = np.asarray(home, dtype=np.float64).copy()
        self.timing.clear()
        self._state = self.device.read()
        now = time.monotonic()
        self._t0 = self._obs_time = now
        self._next_tick = now + self.control_dt
        self.timing.ticks.append(now)
        for layer in self.device.layers:
            layer.arm_watchdog()

    def _settle(self, home: np.ndarray) -> None:
        """Wait (at most ``options.arrive_timeout_s``) until every arm joint is within
        ``options.arrive_tolerance`` of ``home``: the arm lags its trajectory at the end of a
        reset move, and an episode should start where the task says."""
        arm = np.ones(home.shape, dtype=bool)
        arm[[grip for _, grip in self.robot.joint_slices()]] = False
        deadline = time.monotonic() + self.options.arrive_timeout_s
        while True:
            error = float(np.max(np.abs(self.device.read().joints[arm] - home[arm])))
            if error <= self.options.arrive_tolerance:
                return
            if time.monotonic() > deadline:
                log.warning(
                    "%s: reset ended %.4f rad from home (tolerance %.4f rad)",
                    self.robot.name,
                    error,
                    self.options.arrive_tolerance,
                )
                return
            time.sleep(self.control_dt)

    def stop(self) -> None:
        """Stop every arm now and disarm the watchdogs (a fault outside the device: the
        recorder calls it when anything goes wrong mid-episode)."""
        self.device.stop()

    def end_episode(self) -> None:
        """A planned pause in the command stream (the episode is over): disarm the watchdogs
        so that writing the episode does not trip them. The arms hold their last target."""
        for layer in self.device.layers:
            layer.disarm_watchdog()

    def _disarm(self) -> None:
        for layer in self.device.layers:
            if layer.watchdog.tripped:
                log.warning("%s: watchdog had tripped; resuming for the reset", layer.limits.robot)
                layer.resume()
            layer.disarm_watchdog()

    def apply_command(self, command: np.ndarray) -> None:
        self._command = np.asarray(command, dtype=np.float64).copy()

    def step(self) -> None:
        """Send the command, wait for the end of the period, read the arms."""
        if self._command is None:
            raise RuntimeError("reset the env before stepping a real robot")
        self.last_sent = self.device.send(self._command, self.control_dt)
        self.timing.latencies.append(time.monotonic() - self._obs_time)
        self._wait_for_tick()
        self._state = self.device.read()
        self._obs_time = time.monotonic()

    def _wait_for_tick(self) -> None:
        tick, spin = self._next_tick, self.options.spin_s
        now = time.monotonic()
        if now > tick:  # late: count it and start a new schedule from now
            self.timing.overruns += 1
            self._next_tick = now + self.control_dt
            self.timing.ticks.append(now)
            return
        if tick - now > spin:
            time.sleep(tick - now - spin)
        while (now := time.monotonic()) < tick:
            pass
        self.timing.ticks.append(now)
        self._next_tick = tick + self.control_dt

    @property
    def time(self) -> float:
        return time.monotonic() - self._t0

    @property
    def state(self) -> RobotState:
        """The reading taken at the last tick."""
        return self._state

    # ---------------------------------------------------------------- measurements
    def joint_limits(self) -> tuple[tuple[np.ndarray, np.ndarray], ...]:
        return tuple(
            (layer.limits.low_array, layer.limits.high_array) for layer in self.device.layers
        )

    def measured_joint_pos(self) -> np.ndarray:
        return self._state.joints.copy()

    def measured_joint_vel(self) -> np.ndarray:
        return self._state.velocities.copy()

    def measured_wrench(self) -> np.ndarray:
        return self._state.wrench.copy()

    # ---------------------------------------------------------------- cameras
    def render(
        self, cameras: Sequence[str], *, rgb: bool = True, depth: bool = False
    ) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
        """The newest frame of each camera (no waiting: a camera runs at its own rate).

        Raises:
            ValueError: An unknown camera, or depth asked of a colour-only camera.
        """
        rgb_out: dict[str, np.ndarray] = {}
        depth_out: dict[str, np.ndarray] = {}
        for name in cameras:
            if name not in self.device.cameras:
                raise ValueError(f"unknown camera {name!r}; available: {self.cameras}")
            frame = read_frame(self.device.cameras[name], self.device.fovy[name])
            if rgb:
                rgb_out[name] = frame.rgb
            if depth:
                if frame.depth is None:
                    raise ValueError(f"camera {name!r} streams no depth")
                depth_out[name] = frame.depth
        return rgb_out, depth_out

    def fovy(self, camera: str) -> float:
        return self.device.fovy[camera]

    def image_shape(self, camera: str) -> tuple[int, int]:
        cam = self.device.cameras[camera]
        if cam.height is None or cam.width is None:
            return super().image_shape(camera)
        return int(cam.height), int(cam.width)

    # ---------------------------------------------------------------- kinematics
    @property
    def kinematics(self) -> tuple[ArmKinematics, ...]:
        """FK/IK per arm on the robot record's MuJoCo model (built on first use)."""
        if self._kinematics is None:
            from rmb_lerobot.envs.mujoco.kinematics import ArmKinematics
            from rmb_lerobot.envs.mujoco.robots import build_robot_model

            built = build_robot_model(self.robot)
            model = built.spec.compile()
            self._kinematics = tuple(ArmKinematics(model, arm) for arm in built.arms)
        return self._kinematics

    def fk(self, arm: int, q_arm: np.ndarray) -> np.ndarray:
        return self.kinematics[arm].fk(q_arm)

    def ik(self, arm: int, target: np.ndarray, q_init: np.ndarray) -> np.ndarray:
        return self.kinematics[arm].ik(target, q_init).qpos

    def world_to_root(self, arm: int, pos: np.ndarray, rot: np.ndarray) -> np.ndarray:
        return self.kinematics[arm].world_to_root(pos, rot)

    def close(self) -> None:
        """Stop every arm, disconnect and restore the stepping thread's scheduling (safe to
        call twice)."""
        try:
            self.device.disconnect()
        finally:
            if self._previous_policy is not None:
                self._previous_policy.restore()
                self._previous_policy = None
