"""Scripted experts: privileged policies that drive the tool along task waypoints.

An expert is called like any policy, ``action = expert(observation)``, and emits actions in the
env's action mode, so its rollouts can be recorded or evaluated like a learned policy. It reads
object poses from the simulator (privileged information a learned policy does not get).

Experts are written against the robot record's TCP and gripper (:mod:`rmb_lerobot.envs.robots`:
the arm's eef and tool-centre-point frames, the gripper's open and closed commands) and read
the world through the backend's simulator-neutral :class:`~rmb_lerobot.envs.scene.SceneState`,
so one expert serves every robot that shares a task where the geometry allows. They drive one
arm (:attr:`ScriptedExpert.arm_index`, the first).

Control: a reference point moves towards the current waypoint at bounded speed; an integral
term on the measured tool position cancels the steady-state sag of RMB's position-controlled
joints (no gravity compensation, as in RMB); IK turns the corrected tool pose into joint
targets.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from scipy.spatial.transform import Rotation

from rmb_lerobot.envs.backend import Backend
from rmb_lerobot.envs.base import RmbEnv
from rmb_lerobot.envs.scene import SceneState
from rmb_lerobot.keys import MOBILE_OMNI_VEL_DIM
from rmb_lerobot.pose import pose_to_policy, relative_pose


def top_down_rotation(across: np.ndarray, current: Rotation) -> Rotation:
    """Gripper pointing down with the fingers (the eef x axis) closing along the horizontal
    direction ``across``; of the two such orientations, the one nearer the ``current`` hand."""
    across = np.array([across[0], across[1], 0.0])
    across /= np.linalg.norm(across)
    if across @ current.apply([1.0, 0.0, 0.0]) < 0:
        across = -across
    down = np.array([0.0, 0.0, -1.0])
    return Rotation.from_matrix(np.column_stack([across, np.cross(down, across), down]))


def scene_of(env: RmbEnv) -> SceneState:
    """The scene an expert reads (privileged state).

    Raises:
        ValueError: the env's backend has no scene (a real arm): no scripted expert can run.
    """
    scene = env.sim.scene
    if scene is None:
        raise ValueError(
            f"{env.rmb_env_name} has no scene view (a {env.simulator} backend): scripted "
            "experts read object poses and cannot run on it"
        )
    return scene


@dataclass(frozen=True)
class Waypoint:
    """Where the tool point should go (world frame), the eef orientation, the gripper command."""

    pos: np.ndarray
    rot: Rotation
    gripper: float


class ScriptedExpert(ABC):
    """Base of the per-task experts: waypoint tracking with integral correction and IK.

    Subclasses define the tool point (:meth:`tool_offset` in the eef frame and its measured
    world position :meth:`measured_tool`) and the current :meth:`waypoint` (a small state
    machine over the task's phases). Call :meth:`reset` after every ``env.reset``.
    """

    arm_index = 0  # the arm the expert drives
    # Per robot short name: class attributes (the expert's settings) that robot needs other
    # values of, each with the measurement that says why; applied when the expert is made.
    robot_tuning: ClassVar[dict[str, dict[str, Any]]] = {}

    def __init__(
        self,
        env: Any,
        *,
        max_speed: float = 0.15,
        max_angular_speed: float = 1.0,
        integral_gain: float = 0.3,
        max_correction: float = 0.05,
    ):
        self.env: RmbEnv = env.unwrapped
        self.sim: Backend = self.env.sim
        self.scene: SceneState = scene_of(self.env)
        self.arm = self.env.robot.arms[self.arm_index]
        self._arm_joints, self.gripper_index = self.env.robot.joint_slices()[self.arm_index]
        # The gripper's open and closed commands, from the robot record.
        self.open_gripper, self.closed_gripper = self.arm.gripper.open, self.arm.gripper.closed
        self.dt = self.env.control_dt
        self.max_step = max_speed * self.dt
        self.max_angle_step = max_angular_speed * self.dt
        self.integral_gain = integral_gain
        self.max_correction = max_correction
        self._ref_pos = np.zeros(3)
        self._ref_rot = Rotation.identity()
        self._correction = np.zeros(3)
        self._q = self.env.home_command[self._arm_joints].copy()
        for name, value in self.robot_tuning.get(self.env.robot.name, {}).items():
            if not hasattr(type(self), name):
                raise AttributeError(
                    f"{type(self).__name__}.robot_tuning[{self.env.robot.name!r}] names "
                    f"{name!r}, which is not one of its settings"
                )
            setattr(self, name, value)

    # ------------------------------------------------------------------ task hooks
    @abstractmethod
    def tool_offset(self) -> np.ndarray:
        """Tool point in the eef-site frame (3,)."""

    @abstractmethod
    def measured_tool(self) -> np.ndarray:
        """Measured world position of the tool point (3,)."""

    @abstractmethod
    def waypoint(self) -> Waypoint:
        """The current target; may advance the expert's phase."""

    def on_reset(self) -> None:  # noqa: B027 - optional hook
        """Task-specific reset (called once the env state is known)."""

    def base_velocity(self) -> np.ndarray:
        """The base velocity ``(vx, vy, wz)`` (base frame) to command with this step's arm
        target, for a robot on a mobile base (appended to the action); default: stand still."""
        return np.zeros(MOBILE_OMNI_VEL_DIM)

    # ------------------------------------------------------------------ helpers
    def eef_world(self) -> tuple[np.ndarray, Rotation]:
        """Measured eef position and orientation in the world frame."""
        pos, rot = self.scene.site_pose(self.arm.eef_frame)
        return pos, Rotation.from_matrix(rot)

    def tcp_world(self) -> tuple[np.ndarray, np.ndarray]:
        """Measured tool centre point: world position and rotation matrix."""
        return self.scene.site_pose(self.arm.tcp_frame)

    def table_z(self) -> float:
        """Height of the workspace's table top (m)."""
        return self.env.task.workspace.table.top_z

    def reached(self, target: np.ndarray, tol: float, xy_only: bool = False) -> bool:
        """Whether both the reference and the measured tool are within ``tol`` of ``target``."""
        dims = slice(0, 2) if xy_only else slice(0, 3)
        ref_err = np.linalg.norm(self._ref_pos[dims] - target[dims])
        meas_err = np.linalg.norm(self.measured_tool()[dims] - target[dims])
        return bool(ref_err < tol and meas_err < tol)

    # ------------------------------------------------------------------ policy API
    def reset(self) -> None:
        self.on_reset()
        _, rot = self.eef_world()
        self._ref_pos = self.measured_tool()
        self._ref_rot = rot
        self._correction = np.zeros(3)
        self._q = self.env.command[self._arm_joints].copy()

    def __call__(self, observation: Any = None) -> np.ndarray:
        return self.select_action(observation)

    def select_action(self, observation: Any = None) -> np.ndarray:
        """Next action in the env's action mode (the observation itself is not needed)."""
        wp = self.waypoint()
        delta = wp.pos - self._ref_pos
        dist = np.linalg.norm(delta)
        self._ref_pos = self._ref_pos + (
            delta if dist <= self.max_step else delta * (self.max_step / dist)
        )
        rot_err = (wp.rot * self._ref_rot.inv()).as_rotvec()
        angle = np.linalg.norm(rot_err)
        if angle > self.max_angle_step:
            rot_err *= self.max_angle_step / angle
        self._ref_rot = Rotation.from_rotvec(rot_err) * self._ref_rot

        self._correction += self.integral_gain * (self._ref_pos - self.measured_tool())
        norm = np.linalg.norm(self._correction)
        if norm > self.max_correction:
            self._correction *= self.max_correction / norm
        eef_pos = self._ref_pos + self._correction - self._ref_rot.apply(self.tool_offset())
        pose = self.sim.world_to_root(self.arm_index, eef_pos, self._ref_rot.as_matrix())
        return self._action(pose, wp.gripper)

    def _action(self, pose: np.ndarray, gripper: float) -> np.ndarray:
        mode = self.env.action_mode
        if mode == "joint":
            self._q = self.sim.ik(self.arm_index, pose, self._q)
            action = np.append(self._q, gripper)
        elif mode == "eef_abs":
            action = np.append(pose_to_policy(pose), gripper)
        else:
            action = np.append(relative_pose(self.env.command_eef_pose, pose), gripper)
        if self.env.robot.base is not None:
            action = np.concatenate([action, self.base_velocity()])
        return action.astype(np.float32)


class GripperExpert(ScriptedExpert):
    """Base of the experts that grasp with the gripper's pinch point as the tool point.

    The gripper logic the tasks share: wait until the fingers have settled on closing or opening
    (:meth:`_gripper_settled`), restore the cruise speed at every reset (phases may slow the
    reference down), and, for precise placing, track the hand's speed (:meth:`_track_tool_speed`
    once per :meth:`waypoint`) to tell when it is at rest (:meth:`_arrived`) and approach the
    last centimetres slowly (:meth:`_slowly`). Subclasses extend :meth:`on_reset` (calling it
    first) and may override :meth:`measured_tool` to move the tool point onto a held object.
    """

    min_gripper_steps = 10  # steps of closing / opening before the gripper counts as settled
    settle_fraction = 0.5 / 255  # gripper change per step that counts as settled (of its range)
    still_speed = 0.01  # tool speed below which the hand counts as at rest (m/s)
    # The last ``slow_zone`` of an approach with :meth:`_slowly` is done slowly, so the hand
    # arrives at rest (the integral correction does not overshoot) and sets things down softly.
    slow_zone = 0.03  # m

    def __init__(self, env: Any, **kwargs: Any) -> None:
        super().__init__(env, **kwargs)
        self._cruise_step = self.max_step
        low, high = self.arm.gripper.command_range
        self.settle_tol = self.settle_fraction * (high - low)

    def on_reset(self) -> None:
        """Cruise speed, gripper settling and tool speed reset; the pinch point's offset in the
        eef frame measured (it depends on the gripper model only)."""
        self.max_step = self._cruise_step
        self._count = 0
        self._last_gripper = 0.0
        eef_pos, eef_rot = self.eef_world()
        self._offset = eef_rot.inv().apply(self.pinch_point() - eef_pos)
        self._last_tool = self.pinch_point()
        self._tool_speed = 0.0

    def pinch_point(self) -> np.ndarray:
        """Measured world position of the gripper's pinch point (the TCP)."""
        return self.tcp_world()[0]

    def tool_offset(self) -> np.ndarray:
        return self._offset

    def measured_tool(self) -> np.ndarray:
        return self.pinch_point()

    def _gripper_settled(self) -> bool:
        """Called once a step while closing or opening (reset ``_count`` to 0 when a new gripper
        command starts): true once the command has run ``min_gripper_steps`` and the fingers
        have stopped moving, i.e. they hold the object or are fully open."""
        self._count += 1
        gripper = self.env.measured_joint_pos()[self.gripper_index]
        settled = abs(gripper - self._last_gripper) < self.settle_tol
        self._last_gripper = gripper
        return self._count >= self.min_gripper_steps and settled

    def _track_tool_speed(self) -> None:
        """Update the measured tool speed from the last call (call once a step)."""
        tool = self.measured_tool()
        self._tool_speed = float(np.linalg.norm(tool - self._last_tool)) / self.dt
        self._last_tool = tool

    def _arrived(self, target: np.ndarray, tol: float) -> bool:
        """Reference and hand at ``target`` and the hand at rest."""
        return self.reached(target, tol) and self._tool_speed < self.still_speed

    def _slowly(self, target: np.ndarray, speed: float) -> np.ndarray:
        """``target``, but approached at ``speed`` once the reference is within the slow zone."""
        delta = target - self._ref_pos
        dist = np.linalg.norm(delta)
        step = speed * self.dt
        if dist > self.slow_zone or dist <= step:
            return target
        return self._ref_pos + delta * (step / dist)
