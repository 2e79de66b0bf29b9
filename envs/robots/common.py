"""Robots as data: one simulator-neutral record per robot, the one place robot facts live.

A :class:`Robot` is a list of arms (one for a UR5e, two for a dual UR5e); each :class:`Arm` has
its joints, one :class:`Gripper` (command range, open/closed values, how its measured value is
computed), the frames RMB and the experts use (root, end-effector, tool centre point, wrench),
an optional hand camera, the pose it is mounted at and its home pose. A robot may also stand on
a :class:`MobileBase` (driven by a velocity command ``(vx, vy, wz)`` in its own frame) and
carry cameras that are not on a hand (:class:`BodyCamera`: a head camera). From the record
follow the key layout (:attr:`Robot.layout`), the joint vector RMB records (per arm: arm joints,
then the gripper value), the command vector (the joint vector, then the base velocity when
there is a base), the camera names and the names RMB spells (``UR5e`` in
``MujocoUR5eCableEnv``, the ``robot_type`` of converted datasets).

What is neutral and what is not: joint and frame names are those of the robot's model as the
simulator composes it (a MuJoCo backend resolves frames as sites or bodies, another backend
by its own lookup, a real arm by position in the joint vector). How a simulator builds the
robot (which model files, where the gripper attaches, which actuators drive it) is that
simulator's business: :mod:`rmb_lerobot.envs.mujoco.robot` for MuJoCo. Nothing here imports a
simulator, so the env registry and the converters can read robot facts cheaply.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from enum import StrEnum

import numpy as np

from rmb_lerobot.keys import MOBILE_OMNI_VEL_DIM, RobotLayout


@dataclass(frozen=True)
class Pose:
    """A position (m) and unit quaternion ``(w, x, y, z)`` in a parent frame."""

    pos: tuple[float, float, float] = (0.0, 0.0, 0.0)
    quat: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)


@dataclass(frozen=True)
class HandCamera:
    """A camera fixed to an arm's hand frame (:attr:`Arm.hand_frame`), fovy in degrees."""

    name: str
    pose: Pose
    fovy: float


@dataclass(frozen=True)
class BodyCamera:
    """A camera the robot carries on a body that is not a hand (a head camera), fovy in degrees.

    ``parent`` is the body (or frame) it is fixed to, so it moves with a mobile base or a head;
    ``pose`` is its pose in that frame.
    """

    name: str
    parent: str
    pose: Pose
    fovy: float


class GripperKind(StrEnum):
    """What a gripper is; it says what the gripper's command and measured value mean.

    - ``parallel``: a linkage parallel-jaw gripper driven by one motor (Robotiq 2F-85, xArm
      gripper); RMB commands it in driver units, 0 (open) .. 255 (closed).
    - ``slide``: prismatic fingers (Franka hand, WSG50, ViperX); the command is the opening,
      in metres or as RMB's Panda a fraction of the full opening.
    - ``hand``: a multi-finger hand closed along one joint or synergy (the G1's and the HSR's
      hands); the command is that joint's position.
    """

    PARALLEL = "parallel"
    SLIDE = "slide"
    HAND = "hand"


@dataclass(frozen=True)
class Gripper:
    """One gripper: what its command means and how its measured value is computed.

    RMB stores one number per gripper, in the units of its command (0..255 for a Robotiq
    2F-85, 0..1 for the Panda hand). The measured value is ``measured_scale`` times the mean of
    the ``joints`` positions (RMB's formula for every robot it has), so recorded measured and
    command values are comparable.
    """

    joints: tuple[str, ...]
    open: float  # command value of the fully open gripper
    closed: float  # command value of the fully closed gripper
    measured_scale: float
    home: float | None = None  # command at episode start; None: open
    # Per joint +1 or -1: the measured value is measured_scale * mean(sign * position), so
    # fingers that move in opposite directions (a WSG50's: left -g, right +g) both count
    # (RMB's TACTO envs: the mean of |finger positions|). None: every joint +1.
    joint_signs: tuple[float, ...] | None = None
    kind: GripperKind = GripperKind.PARALLEL

    def __post_init__(self) -> None:
        if not self.joints:
            raise ValueError("a gripper needs at least one joint to measure")
        if self.kind not in tuple(GripperKind):
            raise ValueError(
                f"gripper kind must be one of {[k.value for k in GripperKind]}, got {self.kind!r}"
            )
        if self.open == self.closed:
            raise ValueError(f"gripper open and closed values are both {self.open}")
        if self.joint_signs is not None and (
            len(self.joint_signs) != len(self.joints)
            or any(s not in (1.0, -1.0) for s in self.joint_signs)
        ):
            raise ValueError(
                f"gripper joint_signs must be one +1 or -1 per joint {self.joints}, got "
                f"{self.joint_signs}"
            )

    @property
    def signs(self) -> tuple[float, ...]:
        """Per joint the sign its position enters the measured value with."""
        return self.joint_signs if self.joint_signs is not None else (1.0,) * len(self.joints)

    @property
    def command_range(self) -> tuple[float, float]:
        """``(low, high)`` of the command (open and closed, in whichever order they are)."""
        return (min(self.open, self.closed), max(self.open, self.closed))

    @property
    def home_command(self) -> float:
        return self.open if self.home is None else self.home

    def closed_fraction(self, command: float) -> float:
        """How far a command closes the gripper: 0 fully open .. 1 fully closed (clipped).

        The same number for every kind and unit (0..255, metres, a fraction, a hand joint), so
        code that only cares how closed the gripper is need not know which way its units run.
        """
        fraction = (float(command) - self.open) / (self.closed - self.open)
        return float(np.clip(fraction, 0.0, 1.0))


@dataclass(frozen=True)
class MobileBase:
    """An omnidirectional mobile base, commanded by a velocity in its own frame.

    RMB's ``command_mobile_omni_vel`` and ``measured_mobile_omni_vel``: ``(vx, vy, wz)``, the
    linear velocity along the base frame's x and y axes (m/s) and the yaw rate (rad/s). The
    base moves on the floor through three planar ``joints`` (x and y slides, a yaw hinge, as
    RMB's ``mobile_x_joint``, ``mobile_y_joint``, ``mobile_theta_joint``); a simulator measures
    the velocity as those joints' world velocities turned into the base's frame. ``frame`` is
    the base body: the arms and the head cameras ride on it.
    """

    joints: tuple[str, str, str]
    frame: str
    max_linear_vel: float  # bound of |vx| and |vy| commands (m/s)
    max_angular_vel: float  # bound of |wz| commands (rad/s)

    def __post_init__(self) -> None:
        if len(self.joints) != MOBILE_OMNI_VEL_DIM or len(set(self.joints)) != len(self.joints):
            raise ValueError(
                f"a mobile base needs {MOBILE_OMNI_VEL_DIM} distinct joints (x, y, yaw), got "
                f"{self.joints}"
            )
        if not (self.max_linear_vel > 0 and self.max_angular_vel > 0):
            raise ValueError(
                f"mobile base velocity bounds must be > 0, got max_linear_vel="
                f"{self.max_linear_vel}, max_angular_vel={self.max_angular_vel}"
            )

    @property
    def velocity_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """``(low, high)`` of a velocity command ``(vx, vy, wz)``."""
        high = np.array([self.max_linear_vel, self.max_linear_vel, self.max_angular_vel])
        return -high, high


@dataclass(frozen=True)
class Arm:
    """One arm of a robot with its gripper.

    ``root_frame`` is the frame RMB's end-effector poses are given in (the arm's base frame),
    placed in the world at ``mount``; ``eef_frame`` is the pose RMB records (the flange),
    ``tcp_frame`` the tool centre point the scripted experts steer (between the fingers),
    ``hand_frame`` the body the gripper is mounted on (hand camera, wrench sensor, objects
    held by a weld), ``wrench_frame`` where the force/torque sensor measures.
    """

    name: str
    joints: tuple[str, ...]
    home: tuple[float, ...]  # arm joint angles (rad) of the home pose
    gripper: Gripper
    mount: Pose
    root_frame: str
    eef_frame: str
    tcp_frame: str
    hand_frame: str
    wrench_frame: str | None = None
    hand_camera: HandCamera | None = None
    # Fingertip tactile image sensors on the gripper (RMB's rgb_tactile_names), left first.
    tactile_sensors: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if len(self.home) != len(self.joints):
            raise ValueError(
                f"arm {self.name!r}: {len(self.joints)} joints but {len(self.home)} home values"
            )

    @property
    def num_joints(self) -> int:
        """Arm joints plus the gripper value: this arm's share of the joint vector."""
        return len(self.joints) + 1


@dataclass(frozen=True)
class Robot:
    """A robot: its arms, how RMB spells it, and the env names of the original RMB it has.

    ``name`` is the short name used in every derived name (``rmb_ur5e_cable``, the
    ``robot_type`` of converted datasets); ``rmb_name`` is RMB's spelling in environment names
    (``MujocoUR5eCable``). ``rmb_envs``: ``env`` attributes the original RMB writes for this
    robot's environments that our registry does not derive (other simulators, real-robot
    demos), so episodes recorded by RMB itself are recognised exactly. ``base``: the mobile
    base the arms stand on (None: a fixed robot); ``body_cameras``: cameras carried elsewhere
    than on a hand (a head camera).
    """

    name: str
    rmb_name: str
    arms: tuple[Arm, ...]
    rmb_envs: frozenset[str] = frozenset()
    base: MobileBase | None = None
    body_cameras: tuple[BodyCamera, ...] = ()

    def __post_init__(self) -> None:
        if not self.arms:
            raise ValueError(f"robot {self.name!r} has no arm")
        sensors = (*self.cameras, *self.tactile_sensors)
        for what, names in (("arm", [a.name for a in self.arms]), ("camera", sensors)):
            if len(set(names)) != len(names):
                raise ValueError(f"robot {self.name!r}: {what} names repeat: {names}")

    @property
    def layout(self) -> RobotLayout:
        """How many numbers RMB's keys hold for this robot (one eef and gripper per arm)."""
        return RobotLayout(
            num_joints=sum(arm.num_joints for arm in self.arms),
            num_grippers=len(self.arms),
            num_eefs=len(self.arms),
            mobile_dim=MOBILE_OMNI_VEL_DIM if self.base is not None else 0,
        )

    @property
    def command_size(self) -> int:
        """Numbers in a command: the joint vector, then the base velocity if there is a base."""
        layout = self.layout
        return layout.num_joints + layout.mobile_dim

    @property
    def base_slice(self) -> slice | None:
        """Where the base velocity sits in a command (after the joints); None without a base."""
        if self.base is None:
            return None
        start = self.layout.num_joints
        return slice(start, start + MOBILE_OMNI_VEL_DIM)

    @property
    def cameras(self) -> tuple[str, ...]:
        """The robot's own cameras: hand cameras in arm order, then the body cameras."""
        hands = tuple(arm.hand_camera.name for arm in self.arms if arm.hand_camera is not None)
        return (*hands, *(camera.name for camera in self.body_cameras))

    @property
    def tactile_sensors(self) -> tuple[str, ...]:
        """The robot's fingertip tactile image sensors, in arm order."""
        return tuple(name for arm in self.arms for name in arm.tactile_sensors)

    def joint_slices(self) -> tuple[tuple[slice, int], ...]:
        """Per arm: the slice of its arm joints in the joint vector, and its gripper's index."""
        out, start = [], 0
        for arm in self.arms:
            end = start + len(arm.joints)
            out.append((slice(start, end), end))
            start = end + 1
        return tuple(out)

    def home_command(self, arm_homes: tuple[tuple[float, ...], ...] | None = None) -> np.ndarray:
        """The home command: the joint vector as RMB records it (per arm: joints, gripper
        command), then a zero base velocity when the robot has a base (it starts at rest).

        ``arm_homes``: per-arm joint angles replacing the robots' own (a task's start pose).
        """
        homes = arm_homes if arm_homes is not None else tuple(arm.home for arm in self.arms)
        if len(homes) != len(self.arms):
            raise ValueError(f"robot {self.name!r}: {len(self.arms)} arms, {len(homes)} homes")
        values: list[float] = []
        for arm, home in zip(self.arms, homes, strict=True):
            if len(home) != len(arm.joints):
                raise ValueError(
                    f"robot {self.name!r} arm {arm.name!r}: home pose {tuple(home)} has "
                    f"{len(home)} values, expected {len(arm.joints)}"
                )
            values.extend([*home, arm.gripper.home_command])
        if self.base is not None:
            values.extend([0.0] * MOBILE_OMNI_VEL_DIM)
        return np.array(values, dtype=np.float64)


def mounted(robot: Robot, *positions: tuple[float, float, float]) -> Robot:
    """The robot with its arms' bases moved, each keeping its orientation.

    Simulators build a robot where its record mounts it, so this is how to stand one on
    another table or stand.

    Args:
        robot: The record.
        *positions: One base position (m, world frame) per arm, in arm order.

    Returns:
        A copy of the record with those mounts.

    Raises:
        ValueError: If the number of positions is not the number of arms.
    """
    if len(positions) != len(robot.arms):
        raise ValueError(
            f"robot {robot.name!r} has {len(robot.arms)} arms, got {len(positions)} mounts"
        )
    arms = tuple(
        dataclasses.replace(arm, mount=Pose(tuple(pos), arm.mount.quat))
        for arm, pos in zip(robot.arms, positions, strict=True)
    )
    return dataclasses.replace(robot, arms=arms)
