"""Robots as data: one simulator-neutral record per robot, the one place robot facts live.

A :class:`Robot` is a list of arms (one for a UR5e, two for a dual UR5e); each :class:`Arm` has
its joints, one :class:`Gripper` (command range, open/closed values, how its measured value is
computed), the frames RMB and the experts use (root, end-effector, tool centre point, wrench),
an optional hand camera, the pose it is mounted at and its home pose. From the record follow
the key layout (:attr:`Robot.layout`), the joint vector RMB records (per arm: arm joints, then
the gripper value), the camera names and the names RMB spells (``UR5e`` in
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

import numpy as np

from rmb_lerobot.keys import RobotLayout


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

    def __post_init__(self) -> None:
        if not self.joints:
            raise ValueError("a gripper needs at least one joint to measure")
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
    demos), so episodes recorded by RMB itself are recognised exactly.
    """

    name: str
    rmb_name: str
    arms: tuple[Arm, ...]
    rmb_envs: frozenset[str] = frozenset()

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
        )

    @property
    def cameras(self) -> tuple[str, ...]:
        """The robot's own cameras (hand cameras), in arm order."""
        return tuple(arm.hand_camera.name for arm in self.arms if arm.hand_camera is not None)

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
        """The home joint vector as RMB records it (per arm: joints, gripper command).

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
        return np.array(values, dtype=np.float64)


_UR5E_GRIPPER = "gripper/"  # prefix of the Robotiq 2F-85's names inside the composed model

UR5E = Robot(
    name="ur5e",
    rmb_name="UR5e",
    arms=(
        Arm(
            name="arm",
            joints=(
                "shoulder_pan_joint",
                "shoulder_lift_joint",
                "elbow_joint",
                "wrist_1_joint",
                "wrist_2_joint",
                "wrist_3_joint",
            ),
            # RMB's MujocoUR5eInsertEnv start pose (pan towards the table, gripper down).
            home=(np.pi, -np.pi / 2, -0.55 * np.pi, -0.45 * np.pi, np.pi / 2, np.pi / 2),
            gripper=Gripper(
                # RMB: measured gripper = rad2deg(mean of these four angles) / 45 * 255.
                joints=tuple(
                    _UR5E_GRIPPER + name
                    for name in (
                        "right_driver_joint",
                        "right_spring_link_joint",
                        "left_driver_joint",
                        "left_spring_link_joint",
                    )
                ),
                open=0.0,
                closed=255.0,
                measured_scale=255.0 / np.deg2rad(45.0),
            ),
            # RMB's stand: arm base 0.605 m behind the table centre, 0.8 m high, turned by pi
            # about z so that the root frame is the UR DH base frame and the arm faces +x.
            mount=Pose(pos=(-0.605, 0.0, 0.8), quat=(0.0, 0.0, 0.0, 1.0)),
            root_frame="ur5e_root_frame",
            eef_frame="attachment_site",
            tcp_frame=_UR5E_GRIPPER + "pinch",
            hand_frame=_UR5E_GRIPPER + "base_mount",
            wrench_frame=_UR5E_GRIPPER + "ft_site",
            # RMB's wrist D435i: 5 cm off the tool axis, looking along the gripper, fovy 62 deg.
            hand_camera=HandCamera("hand", Pose(pos=(0.0, 0.05, 0.0), quat=(0, 0, 1, 0)), 62.0),
        ),
    ),
    # The original RMB's single-arm UR5e envs (gymnasium spec names, as its recorder writes
    # them) that the registry does not derive: other simulators, real demos, and RMB's single
    # Cabinet (ours are CabinetHinge and CabinetSlide).
    rmb_envs=frozenset(
        {
            "MujocoUR5eCabinetEnv",
            "IsaacUR5eChainEnv",
            "IsaacUR5eCabinetEnv",
            "RealUR5eDemoEnv",
        }
    ),
)


def _ur5e_arm(side: str, mount_y: float, home: tuple[float, ...]) -> Arm:
    """One arm of RMB's dual UR5e: the single UR5e's arm under the ``<side>/`` name prefix,
    mounted ``mount_y`` off the centre line, with its own hand camera ``<side>_hand``."""
    prefix = f"{side}/"
    arm = UR5E.arms[0]

    def named(name: str) -> str:
        return prefix + name

    return Arm(
        name=side,
        joints=tuple(map(named, arm.joints)),
        home=home,
        gripper=Gripper(
            joints=tuple(map(named, arm.gripper.joints)),
            open=arm.gripper.open,
            closed=arm.gripper.closed,
            measured_scale=arm.gripper.measured_scale,
        ),
        mount=Pose(pos=(arm.mount.pos[0], mount_y, arm.mount.pos[2]), quat=arm.mount.quat),
        root_frame=named(arm.root_frame),
        eef_frame=named(arm.eef_frame),
        tcp_frame=named(arm.tcp_frame),
        hand_frame=named(arm.hand_frame),
        wrench_frame=named(arm.wrench_frame) if arm.wrench_frame else None,
        hand_camera=HandCamera(f"{side}_hand", arm.hand_camera.pose, arm.hand_camera.fovy)
        if arm.hand_camera
        else None,
    )


UR5E_DUAL = Robot(
    name="ur5e_dual",
    rmb_name="UR5eDual",
    # env_ur5e_dual_cable.xml: left/ and right/ arms at y = +-0.4 on one 1.32 m stand; the
    # start pose of MujocoUR5eDualCableEnv.py (RMB has no other dual MuJoCo env).
    arms=(
        _ur5e_arm(
            "left",
            0.4,
            tuple(float(q) for q in np.pi * np.array([0.9, -0.4, -0.65, -0.2, 0.5, 0.5])),
        ),
        _ur5e_arm(
            "right",
            -0.4,
            tuple(float(q) for q in np.pi * np.array([0.1, -0.6, 0.65, -0.8, -0.5, -0.5])),
        ),
    ),
    rmb_envs=frozenset({"RealUR5eDualDemoEnv"}),
)

XARM7 = Robot(
    name="xarm7",
    rmb_name="Xarm7",
    arms=(
        Arm(
            name="arm",
            joints=tuple(f"joint{i}" for i in range(1, 8)),
            # MujocoXarm7CableEnv.py line 20 (also PushT's start pose).
            home=(0.0, 0.0, 0.0, 0.8, 0.0, 0.8, 0.0),
            gripper=Gripper(
                # MujocoXarm7EnvBase._get_obs: measured = mean of these six angles / 0.8 * 255.
                joints=(
                    "left_driver_joint",
                    "left_finger_joint",
                    "left_inner_knuckle_joint",
                    "right_driver_joint",
                    "right_finger_joint",
                    "right_inner_knuckle_joint",
                ),
                open=0.0,
                closed=255.0,
                measured_scale=255.0 / 0.8,
            ),
            # env_xarm7_*.xml: xarm7_root_frame on RMB's xArm table, 0.22 m behind its centre.
            mount=Pose(pos=(-0.22, 0.0, 0.74)),
            root_frame="xarm7_root_frame",
            eef_frame="eef",  # on link7 at joint 7 (RMB's IK frame, ik_eef_joint_id 7)
            tcp_frame="link_tcp",
            hand_frame="link7",  # the gripper and the camera are mounted on link 7
            wrench_frame="ft_site",
            # xarm7_body.xml lines 104-108: the wrist D435 on link7, fovy 62 deg; the quaternion
            # of RMB's euler="0 3.1415 1.5708" (3.1415, not pi).
            hand_camera=HandCamera(
                "hand",
                Pose(
                    pos=(0.06746, 0.0, 0.0237),
                    quat=(3.2757930e-05, 0.70710808, 0.70710548, 3.2758051e-05),
                ),
                62.0,
            ),
        ),
    ),
    rmb_envs=frozenset({"RealXarm7DemoEnv"}),
)

PANDA = Robot(
    name="panda",
    rmb_name="Panda",
    arms=(
        Arm(
            name="arm",
            joints=tuple(f"joint{i}" for i in range(1, 8)),
            # MujocoPandaCableEnv.py lines 20-30.
            home=tuple(float(q) for q in np.deg2rad([0, 25, 0, -58, 0, 82, -40])),
            gripper=Gripper(
                # RMB's command is the finger opening, 0 (closed) .. 1 (0.04 m each finger);
                # measured = mean(fingers) / 0.04 (MujocoPandaEnvBase.py line 106).
                joints=("finger_joint1", "finger_joint2"),
                open=1.0,
                closed=0.0,
                measured_scale=1.0 / 0.04,
            ),
            # env_panda_cable.xml line 36: panda_root_frame on RMB's stand.
            mount=Pose(pos=(-0.5, 0.0, 0.8)),
            root_frame="panda_root_frame",
            eef_frame="eef",  # on panda_link7 (the flange)
            tcp_frame="pinch",  # between the fingertip pads (franka_ros panda_hand_tcp)
            hand_frame="panda_hand",
            wrench_frame="ft_site",
        ),
    ),
)

SAWYER = Robot(
    name="sawyer",
    rmb_name="Sawyer",
    arms=(
        Arm(
            name="arm",
            joints=tuple(f"right_j{i}" for i in range(7)),
            # RMB's TactoSawyerGrasp/Insert start pose (TactoSawyerGraspEnv.py:16-28).
            home=(0.0, -1.24, -0.58, 2.18, 0.27, 0.7, 1.0),
            # The WSG50's prismatic fingers go to (-g, +g) for command g (metres, larger is
            # wider; RMB's joint limits 0.0027..0.055); RMB measures mean |finger position|.
            gripper=Gripper(
                joints=("base_joint_gripper_left", "base_joint_gripper_right"),
                open=0.055,
                closed=0.0027,
                measured_scale=1.0,
                home=0.02,
                joint_signs=(-1.0, 1.0),
            ),
            # RMB asks for the base at (0, 0, 0.1); pybulletX puts the base's centre of mass
            # there, so the root link frame is at (0.1, 0, 0.03) (envs/pybullet/sawyer.py).
            mount=Pose(pos=(0.1, 0.0, 0.03)),
            root_frame="base",
            eef_frame="right_l6",  # RMB's IK end effector (Pinocchio joint 7 of sawyer.urdf)
            tcp_frame="tool_centre",  # between the two DIGIT gel pads
            hand_frame="right_hand",
            wrench_frame="right_hand",  # RMB's F/T joint
            tactile_sensors=("tactile_left", "tactile_right"),
        ),
    ),
)
"""RMB's TACTO robot: a Rethink Sawyer with a Weiss WSG50 gripper and a DIGIT tactile sensor on
each fingertip (PyBullet)."""


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


ROBOTS: dict[str, Robot] = {robot.name: robot for robot in (UR5E, UR5E_DUAL, XARM7, PANDA, SAWYER)}
"""Every robot by short name."""


def robot_for(name: str) -> Robot:
    """A robot record by short name; the error lists the known ones."""
    try:
        return ROBOTS[name]
    except KeyError:
        raise ValueError(f"unknown robot {name!r}; known: {', '.join(sorted(ROBOTS))}") from None
