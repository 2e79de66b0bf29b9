"""The RMB key catalogue: every data key and file attribute name, with its dimension.

This module is the single source of truth for names; the episode reader/writer, converters,
envs and policies import from here instead of re-typing strings. Names and shapes follow the
original RoboManipBaselines ``DataKey`` so files stay interchangeable.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from enum import StrEnum

from rmb_lerobot.pose import POLICY_POSE_DIM, POSE_DIM, REL_POSE_DIM

# ---------------------------------------------------------------- scalar keys
TIME = "time"
REWARD = "reward"

MEASURED = "measured"
COMMAND = "command"
REL_SUFFIX = "_rel"

# ---------------------------------------------------------------- image keys
RGB_IMAGE_SUFFIX = "_rgb_image"
DEPTH_IMAGE_SUFFIX = "_depth_image"
POINTCLOUD_SUFFIX = "_pointcloud"
FOVY_ATTR_SUFFIX = "_fovy"
CAMERA_POSE_ATTR_SUFFIX = "_pose"

# ---------------------------------------------------------------- file attributes
ATTR_FORMAT = "format"
ATTR_DEMO_NAME = "demo_name"
ATTR_TASK_DESC = "task_desc"
ATTR_VERSION = "version"
ATTR_ENV = "env"
ATTR_WORLD_IDX = "world_idx"
ATTR_CAMERA_NAMES = "camera_names"
ATTR_RGB_TACTILE_NAMES = "rgb_tactile_names"
ATTR_POINTCLOUD_CAMERA_NAMES = "pointcloud_camera_names"
# Attribute names that hold a list of strings (stored as variable-length string arrays).
STRING_LIST_ATTRS = (ATTR_CAMERA_NAMES, ATTR_RGB_TACTILE_NAMES, ATTR_POINTCLOUD_CAMERA_NAMES)

FORMAT_COMPACT = "RmbData-Compact"
FORMAT_SINGLE_HDF5 = "RmbData-SingleHDF5"
# The RMB release whose file layout we write (the original stores its package version here).
RMB_FORMAT_VERSION = "3.0.0"

COMPACT_SUFFIX = ".rmb"
SINGLE_HDF5_SUFFIX = ".hdf5"
COMPACT_MAIN_FILE = "main.rmb.hdf5"


class Quantity(StrEnum):
    """Physical quantities RMB records, each with a measured and a command key."""

    JOINT_POS = "joint_pos"
    JOINT_VEL = "joint_vel"
    JOINT_TORQUE = "joint_torque"
    GRIPPER_JOINT_POS = "gripper_joint_pos"
    EEF_POSE = "eef_pose"
    EEF_VEL = "eef_vel"
    EEF_WRENCH = "eef_wrench"
    MOBILE_OMNI_VEL = "mobile_omni_vel"


# Numbers of a mobile base velocity: (vx, vy, wz) in the base's own frame (m/s, m/s, rad/s).
MOBILE_OMNI_VEL_DIM = 3

# Quantities that have a ``_rel`` (difference from the previous step) variant.
RELATIVE_QUANTITIES = (Quantity.JOINT_POS, Quantity.GRIPPER_JOINT_POS, Quantity.EEF_POSE)


@dataclass(frozen=True)
class RobotLayout:
    """How many numbers a robot's keys hold.

    ``num_joints`` counts what ``*_joint_pos`` stores: arm joints plus one value per gripper
    (a UR5e with a Robotiq gripper stores 6 + 1 = 7). A robot on a mobile base also records
    its base velocity (``*_mobile_omni_vel``, ``mobile_dim`` numbers) apart from the joints.
    """

    num_joints: int
    num_grippers: int = 1
    num_eefs: int = 1
    # Numbers of the mobile base's velocity (``*_mobile_omni_vel``): MOBILE_OMNI_VEL_DIM for a
    # robot with a base, 0 for a fixed one.
    mobile_dim: int = 0

    def __post_init__(self) -> None:
        if self.mobile_dim not in (0, MOBILE_OMNI_VEL_DIM):
            raise ValueError(
                f"RobotLayout mobile_dim must be 0 (no base) or {MOBILE_OMNI_VEL_DIM}, "
                f"got {self.mobile_dim}"
            )

    def arm_groups(self) -> tuple[tuple[range, range], ...]:
        """Per arm, the indices of its arm joints and of its gripper value(s) in a joint vector.

        RMB orders a multi-arm joint vector arm by arm, each arm's joints then its gripper
        (the dual UR5e: 6 + 1 left, 6 + 1 right). One gripper per arm; a vector that does not
        split evenly into ``num_grippers`` arms is read as one arm: joints, then grippers.
        """
        n, g = self.num_joints, self.num_grippers
        if g <= 1 or n % g:
            return ((range(0, n - g), range(n - g, n)),)
        per_arm = n // g
        return tuple(
            (range(start, start + per_arm - 1), range(start + per_arm - 1, start + per_arm))
            for start in range(0, n, per_arm)
        )


UR5E_LAYOUT = RobotLayout(num_joints=7)


def layout_for_env(env: object) -> RobotLayout | None:
    """The layout of the robot an episode's ``env`` attribute names, or None if unknown.

    Names match exactly (``MujocoUR5eDualCableEnv`` is two arms, not a UR5e): the env
    registry's attributes and the original RMB's env names its robot records list (see
    :func:`rmb_lerobot.envs.registry.robot_for_env_attr`, the one place that maps env names to
    robots).
    """
    from rmb_lerobot.envs.registry import robot_for_env_attr  # imported with rmb_lerobot anyway

    robot = robot_for_env_attr(env)
    return robot.layout if robot is not None else None


@dataclass(frozen=True)
class KeySpec:
    """One low-dimensional RMB key."""

    name: str
    quantity: Quantity | None
    source: str | None  # MEASURED, COMMAND, or None for time/reward
    is_relative: bool = False

    def dim(self, layout: RobotLayout) -> int:
        """Numbers per step as stored in the file (0 for scalar keys stored as ``(T,)``)."""
        if self.quantity is None:
            return 0
        if self.quantity in (Quantity.JOINT_POS, Quantity.JOINT_VEL, Quantity.JOINT_TORQUE):
            return layout.num_joints
        if self.quantity is Quantity.GRIPPER_JOINT_POS:
            return layout.num_grippers
        if self.quantity is Quantity.EEF_POSE:
            return (REL_POSE_DIM if self.is_relative else POSE_DIM) * layout.num_eefs
        if self.quantity in (Quantity.EEF_VEL, Quantity.EEF_WRENCH):
            return 6 * layout.num_eefs
        return MOBILE_OMNI_VEL_DIM  # MOBILE_OMNI_VEL: vx, vy, wz

    def policy_dim(self, layout: RobotLayout) -> int:
        """Numbers per step as policies see them (absolute eef poses become 9 numbers)."""
        if self.quantity is Quantity.EEF_POSE and not self.is_relative:
            return POLICY_POSE_DIM * layout.num_eefs
        return max(self.dim(layout), 1)


def _key_name(source: str, quantity: Quantity, relative: bool = False) -> str:
    return f"{source}_{quantity.value}{REL_SUFFIX if relative else ''}"


def _build_catalogue() -> dict[str, KeySpec]:
    specs = [KeySpec(TIME, None, None), KeySpec(REWARD, None, None)]
    for quantity in Quantity:
        for source in (MEASURED, COMMAND):
            specs.append(KeySpec(_key_name(source, quantity), quantity, source))
            if quantity in RELATIVE_QUANTITIES:
                specs.append(KeySpec(_key_name(source, quantity, True), quantity, source, True))
    return {spec.name: spec for spec in specs}


KEYS: dict[str, KeySpec] = _build_catalogue()
"""Every low-dimensional key RMB knows, by name."""

MEASURED_JOINT_POS = "measured_joint_pos"
COMMAND_JOINT_POS = "command_joint_pos"
MEASURED_JOINT_VEL = "measured_joint_vel"
COMMAND_JOINT_VEL = "command_joint_vel"
MEASURED_JOINT_TORQUE = "measured_joint_torque"
COMMAND_JOINT_TORQUE = "command_joint_torque"
MEASURED_GRIPPER_JOINT_POS = "measured_gripper_joint_pos"
COMMAND_GRIPPER_JOINT_POS = "command_gripper_joint_pos"
MEASURED_EEF_POSE = "measured_eef_pose"
COMMAND_EEF_POSE = "command_eef_pose"
MEASURED_EEF_VEL = "measured_eef_vel"
COMMAND_EEF_VEL = "command_eef_vel"
MEASURED_EEF_WRENCH = "measured_eef_wrench"
COMMAND_EEF_WRENCH = "command_eef_wrench"
MEASURED_MOBILE_OMNI_VEL = "measured_mobile_omni_vel"
COMMAND_MOBILE_OMNI_VEL = "command_mobile_omni_vel"
MEASURED_JOINT_POS_REL = "measured_joint_pos_rel"
COMMAND_JOINT_POS_REL = "command_joint_pos_rel"
MEASURED_GRIPPER_JOINT_POS_REL = "measured_gripper_joint_pos_rel"
COMMAND_GRIPPER_JOINT_POS_REL = "command_gripper_joint_pos_rel"
MEASURED_EEF_POSE_REL = "measured_eef_pose_rel"
COMMAND_EEF_POSE_REL = "command_eef_pose_rel"

MEASURED_KEYS = tuple(name for name, spec in KEYS.items() if spec.source == MEASURED)
COMMAND_KEYS = tuple(name for name, spec in KEYS.items() if spec.source == COMMAND)
RELATIVE_KEYS = tuple(name for name, spec in KEYS.items() if spec.is_relative)


def spec(key: str) -> KeySpec:
    """The catalogue entry of a low-dimensional key; ``KeyError`` names unknown keys."""
    try:
        return KEYS[key]
    except KeyError:
        raise KeyError(f"unknown RMB key {key!r}; known keys: {sorted(KEYS)}") from None


def is_relative_key(key: str) -> bool:
    return key in KEYS and KEYS[key].is_relative


def abs_key(key: str) -> str:
    """``command_eef_pose_rel`` -> ``command_eef_pose`` (absolute keys map to themselves)."""
    return key.removesuffix(REL_SUFFIX) if is_relative_key(key) else spec(key).name


def rel_key(key: str) -> str:
    """``measured_joint_pos`` -> ``measured_joint_pos_rel``; error for keys without one."""
    s = spec(key)
    if s.is_relative:
        return key
    if s.quantity not in RELATIVE_QUANTITIES:
        raise KeyError(f"RMB key {key!r} has no relative variant")
    return key + REL_SUFFIX


def measured_key(key: str) -> str:
    """The measured counterpart of a command key (and the identity on measured keys)."""
    s = spec(key)
    if s.source is None:
        raise KeyError(f"RMB key {key!r} has no measured/command pair")
    return _key_name(MEASURED, s.quantity, s.is_relative)


def command_key(key: str) -> str:
    """The command counterpart of a measured key (and the identity on command keys)."""
    s = spec(key)
    if s.source is None:
        raise KeyError(f"RMB key {key!r} has no measured/command pair")
    return _key_name(COMMAND, s.quantity, s.is_relative)


# ---------------------------------------------------------------- tactile grids
# RMB stores each MuJoCo tactile sensor (isri-aist's plugin) under the sensor's name, one
# (rows, cols) grid of normal forces (N) per step; RMB's UR5e has one per 2F-85 fingertip pad.
TACTILE_SUFFIX = "_tactile_sensor"
LEFT_TACTILE_SENSOR = "left" + TACTILE_SUFFIX
RIGHT_TACTILE_SENSOR = "right" + TACTILE_SUFFIX
TACTILE_SHAPE = (5, 8)  # rows along the pad's width, columns along the finger


def is_tactile_key(key: str) -> bool:
    return key.endswith(TACTILE_SUFFIX)


# ---------------------------------------------------------------- cameras
def rgb_image_key(camera: str) -> str:
    return camera + RGB_IMAGE_SUFFIX


def depth_image_key(camera: str) -> str:
    return camera + DEPTH_IMAGE_SUFFIX


def pointcloud_key(camera: str) -> str:
    return camera + POINTCLOUD_SUFFIX


def fovy_attr(camera: str) -> str:
    """Attribute holding a camera's vertical field of view in degrees (RMB's only intrinsic)."""
    return depth_image_key(camera) + FOVY_ATTR_SUFFIX


def camera_pose_attr(camera: str) -> str:
    """Attribute holding a fixed camera's world pose (``front_depth_image_pose``).

    A 4x4 world-from-camera transform in metres, camera axes as OpenCV's and
    :func:`rmb_lerobot.pointcloud.depth_to_points`' (x right, y down, z forward), so
    ``world = pose @ [x, y, z, 1]`` for a back-projected depth point. Recorded only for cameras
    fixed to the world (not the hand cameras), next to :func:`fovy_attr`.
    """
    return depth_image_key(camera) + CAMERA_POSE_ATTR_SUFFIX


def is_rgb_image_key(key: str) -> bool:
    return key.endswith(RGB_IMAGE_SUFFIX)


def is_depth_image_key(key: str) -> bool:
    return key.endswith(DEPTH_IMAGE_SUFFIX)


def is_pointcloud_key(key: str) -> bool:
    return key.endswith(POINTCLOUD_SUFFIX)


def is_image_key(key: str) -> bool:
    """Keys stored as video in the compact format."""
    return is_rgb_image_key(key) or is_depth_image_key(key)


def camera_of(key: str) -> str:
    """``front_rgb_image`` -> ``front``; ``ValueError`` for keys that are not camera keys."""
    for suffix in (RGB_IMAGE_SUFFIX, DEPTH_IMAGE_SUFFIX, POINTCLOUD_SUFFIX):
        if key.endswith(suffix):
            return key.removesuffix(suffix)
    raise ValueError(f"{key!r} is not a camera key (*{RGB_IMAGE_SUFFIX}, *{DEPTH_IMAGE_SUFFIX})")


def camera_keys(cameras: Iterable[str], *, rgb: bool = True, depth: bool = True) -> list[str]:
    """Image keys of the given cameras, RGB then depth per camera."""
    keys = []
    for camera in cameras:
        if rgb:
            keys.append(rgb_image_key(camera))
        if depth:
            keys.append(depth_image_key(camera))
    return keys
