"""What every robot model builder shares: the MuJoCo names a robot record needs, MjSpec edits.

A builder takes the robot's record (:class:`~rmb_lerobot.envs.robots.Robot`) and returns a
:class:`RobotModel`: the composed :class:`mujoco.MjSpec` (the root of the scene, like
:func:`rmb_lerobot.envs.mujoco.robot.build_robot_spec`'s) and one :class:`ArmModel` per arm,
which holds the arm's record and adds only what MuJoCo names (actuators, base body, sensors,
hand camera).
"""

from __future__ import annotations

import importlib.metadata
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from rmb_lerobot.envs.robots import Arm

ERD_DISTRIBUTION = "example-robot-data"
ERD_REQUIREMENT = "example-robot-data>=6.0,<7"
_ERD_ROBOTS = "cmeel.prefix/share/example-robot-data/robots"
_ERD_PACKAGE_URL = "package://example-robot-data/robots/"

# Names of the wrist wrench sensors (the UR5e's; every MuJoCo robot here uses them).
FORCE_SENSOR = "force"
TORQUE_SENSOR = "torque"

Vec3 = tuple[float, float, float]
Quat = tuple[float, float, float, float]


@dataclass(frozen=True)
class ArmModel:
    """One arm of a :class:`RobotModel`: its robot record and the names only MuJoCo has.

    The neutral facts (joints, gripper, home, frames) are the record's (:attr:`record`, an
    :class:`~rmb_lerobot.envs.robots.Arm`), read through the properties below under
    :class:`~rmb_lerobot.envs.mujoco.robot.RobotSpec`'s names so that code written against
    those (e.g. :class:`~rmb_lerobot.envs.mujoco.kinematics.ArmKinematics`) reads it. The
    fields are what a MuJoCo model adds: actuators, the arm's base body, the wrench sensors and
    the hand camera's MuJoCo name. :func:`~rmb_lerobot.envs.mujoco.robots.check_model` proves
    that a compiled model has every name the record gives.

    The measured gripper value is ``measured_scale * mean(sign * gripper joint positions)``, in
    the units of the gripper actuator's command (:meth:`gripper_value`), as RMB computes it.
    End-effector poses are ``eef_site`` poses in the ``root_body`` frame (RMB's
    ``*_root_frame``); ``tcp_site`` is between the fingertips.
    """

    record: Arm
    arm_actuators: tuple[str, ...]
    gripper_actuator: str
    base_body: str
    force_sensor: str
    torque_sensor: str
    hand_camera: str | None

    def __post_init__(self) -> None:
        if len(self.arm_actuators) != len(self.record.joints):
            raise ValueError(
                f"arm {self.record.name!r}: {len(self.record.joints)} joints but "
                f"{len(self.arm_actuators)} actuators {self.arm_actuators}"
            )

    @property
    def arm_joints(self) -> tuple[str, ...]:
        return self.record.joints

    @property
    def gripper_joints(self) -> tuple[str, ...]:
        return self.record.gripper.joints

    @property
    def gripper_scale(self) -> float:
        return self.record.gripper.measured_scale

    @property
    def gripper_ctrl_range(self) -> tuple[float, float]:
        return self.record.gripper.command_range

    @property
    def home_arm_qpos(self) -> tuple[float, ...]:
        return self.record.home

    @property
    def home_gripper(self) -> float:
        return self.record.gripper.home_command

    @property
    def root_body(self) -> str:
        return self.record.root_frame

    @property
    def eef_site(self) -> str:
        return self.record.eef_frame

    @property
    def tcp_site(self) -> str:
        return self.record.tcp_frame

    @property
    def ft_site(self) -> str | None:
        return self.record.wrench_frame

    @property
    def num_arm_joints(self) -> int:
        return len(self.arm_joints)

    @property
    def home_qpos(self) -> np.ndarray:
        """Home joint vector as RMB records it (arm joints + gripper command value)."""
        return np.array([*self.home_arm_qpos, self.home_gripper])

    def gripper_value(self, data: mujoco.MjData) -> float:
        """The measured gripper value RMB records for this arm."""
        gripper = self.record.gripper
        positions = [data.joint(name).qpos[0] for name in gripper.joints]
        return gripper.measured_scale * float(
            np.mean([sign * q for sign, q in zip(gripper.signs, positions, strict=True)])
        )

    def set_home(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        """Arm joints at home and their actuators (and the gripper's) commanding it."""
        for joint, actuator, q in zip(
            self.arm_joints, self.arm_actuators, self.home_arm_qpos, strict=True
        ):
            data.joint(joint).qpos[0] = q
            data.actuator(actuator).ctrl[0] = q
        data.actuator(self.gripper_actuator).ctrl[0] = self.home_gripper
        mujoco.mj_forward(model, data)


@dataclass(frozen=True)
class StandBox:
    """RMB's robot stand (world frame): box centre and half sizes."""

    pos: Vec3
    half_size: Vec3


@dataclass(frozen=True)
class RobotModel:
    """A composed robot: ``spec`` to add a scene to, and the names of each arm in it.

    ``cameras`` maps the camera names RMB records (``hand``, ``left_hand``) to the MuJoCo names.
    ``stand`` is RMB's stand under the robot, or ``None`` where RMB puts it on the table.
    """

    name: str
    spec: mujoco.MjSpec
    arms: tuple[ArmModel, ...]
    cameras: dict[str, str]
    stand: StandBox | None


# --------------------------------------------------------------------------- example-robot-data
def erd_robots_dir() -> Path:
    """``robots/`` of the installed example-robot-data (a cmeel wheel: data, no Python module,
    so it is found through its distribution metadata, without importing anything)."""
    try:
        dist = importlib.metadata.distribution(ERD_DISTRIBUTION)
    except importlib.metadata.PackageNotFoundError:
        raise ModuleNotFoundError(
            f"the xArm7 and Panda models need the '{ERD_DISTRIBUTION}' package, which is not "
            f"installed: pip install '{ERD_REQUIREMENT}'",
            name=ERD_DISTRIBUTION,
        ) from None
    robots = Path(str(dist.locate_file(_ERD_ROBOTS)))
    if not robots.is_dir():
        raise ModuleNotFoundError(
            f"'{ERD_DISTRIBUTION}' {dist.version} has no {_ERD_ROBOTS} directory; "
            f"expected {ERD_REQUIREMENT}",
            name=ERD_DISTRIBUTION,
        )
    return robots


def load_erd_urdf(relative: str) -> tuple[mujoco.MjSpec, Path]:
    """An example-robot-data URDF as an MjSpec that compiles and composes; and its path.

    - ``package://`` mesh paths become absolute (MuJoCo cannot resolve them; ``meshdir`` +
      ``strippath`` would compile too, but :mod:`~rmb_lerobot.envs.mujoco.meshes` keys its cache
      on ``mesh.file``);
    - ``fusestatic`` off: the URDF importer's default would fuse fixed links (``link_base``,
      the Panda hand) into their parents, leaving nothing to mount or attach to;
    - ``discardvisual`` off: the URDF importer's default would make the compiler drop every
      render-only geom of the composed model (attached grippers, render twins, cameras' boxes).
      URDF ``<visual>`` elements are dropped while parsing anyway.
    """
    robots = erd_robots_dir()
    path = robots / relative
    spec = mujoco.MjSpec.from_file(str(path))
    for mesh in spec.meshes:
        if mesh.file.startswith(_ERD_PACKAGE_URL):
            mesh.file = str(robots / mesh.file.removeprefix(_ERD_PACKAGE_URL))
    spec.compiler.fusestatic = False
    spec.compiler.discardvisual = False
    return spec, path


# --------------------------------------------------------------------------- spec edits
def add_servo(
    spec: mujoco.MjSpec,
    name: str,
    target: str,
    *,
    kp: float,
    kv: float,
    ctrl_range: tuple[float, float],
    force_range: tuple[float, float] | None = None,
    gain: float | None = None,
    gear: float = 1.0,
    trn: mujoco.mjtTrn = mujoco.mjtTrn.mjTRN_JOINT,
) -> mujoco.MjsActuator:
    """MJCF ``<general biastype="affine">`` position servo: force ``gain * ctrl - kp * l -
    kv * ldot`` on the actuator length ``l = gear * q`` (``gain`` defaults to ``kp``: with
    gear 1 the command is the target position)."""
    act = spec.add_actuator(name=name, target=target, trntype=trn)
    act.gear[0] = gear
    act.gaintype = mujoco.mjtGain.mjGAIN_FIXED
    act.biastype = mujoco.mjtBias.mjBIAS_AFFINE
    act.gainprm[0] = kp if gain is None else gain
    act.biasprm[0:3] = [0.0, -kp, -kv]
    act.ctrlrange = list(ctrl_range)
    act.ctrllimited = mujoco.mjtLimited.mjLIMITED_TRUE
    if force_range is not None:
        act.forcerange = list(force_range)
        act.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
    return act


def add_arm_servos(
    spec: mujoco.MjSpec,
    joints: tuple[str, ...],
    actuators: tuple[str, ...],
    gains: tuple[tuple[float, float, float], ...],
) -> None:
    """One position servo per arm joint, ``(kp, kv, max force)`` each, commanding the joint's
    own range (RMB's arm actuators)."""
    for joint, actuator, (kp, kv, force) in zip(joints, actuators, gains, strict=True):
        add_servo(
            spec,
            actuator,
            joint,
            kp=kp,
            kv=kv,
            ctrl_range=tuple(spec.joint(joint).range),
            force_range=(-force, force),
        )


def add_render_twins(spec: mujoco.MjSpec, rgba: tuple[float, ...] | None = None) -> int:
    """Give every colliding, rendered mesh geom a render-only twin (group 2) and hide the
    original in group 3; returns how many. Physics is unchanged (same geoms collide, bodies
    have explicit inertials) and :func:`~rmb_lerobot.envs.mujoco.meshes.simplify_visual_meshes`
    can then simplify what is drawn, which it never does for colliding geoms."""
    count = 0
    for body in spec.bodies:
        for geom in list(body.geoms):
            collides = geom.contype or geom.conaffinity
            if geom.type != mujoco.mjtGeom.mjGEOM_MESH or not collides or geom.group >= 3:
                continue
            if not body.explicitinertial:
                raise ValueError(f"body {body.name!r} infers its inertia from its geoms")
            body.add_geom(
                type=geom.type,
                meshname=geom.meshname,
                pos=list(geom.pos),
                quat=list(geom.quat),
                material=geom.material,
                rgba=list(geom.rgba if rgba is None else rgba),
                contype=0,
                conaffinity=0,
                group=2,
            )
            geom.group = 3
            count += 1
    return count


def euler_quat(euler: tuple[float, float, float]) -> list[float]:
    """MJCF ``euler`` (default ``eulerseq="xyz"``, radians) as a quaternion."""
    quat = np.empty(4)
    mujoco.mju_euler2Quat(quat, np.asarray(euler, dtype=np.float64), "xyz")
    return quat.tolist()


def mount(
    spec: mujoco.MjSpec, base_body: str, root_body: str, pos: Vec3, quat: Quat = (1, 0, 0, 0)
) -> None:
    """Place the arm's base at the mount pose (composed with its own pose) and add the static,
    geometry-free ``root_body`` marking the frame eef poses refer to (RMB's ``*_root_frame``)."""
    mount_quat = np.asarray(quat, dtype=np.float64)
    mount_mat = np.empty(9)
    mujoco.mju_quat2Mat(mount_mat, mount_quat)
    base = spec.body(base_body)
    base_quat = np.empty(4)
    mujoco.mju_mulQuat(base_quat, mount_quat, np.asarray(base.quat, dtype=np.float64))
    base.pos = np.asarray(pos) + mount_mat.reshape(3, 3) @ np.asarray(base.pos)
    base.quat = base_quat
    spec.worldbody.add_body(name=root_body, pos=list(pos), quat=list(mount_quat))


def add_ft_sensor(
    spec: mujoco.MjSpec, body: str, site: str, quat: Quat = (1, 0, 0, 0)
) -> tuple[str, str]:
    """A site on ``body`` with a force and a torque sensor (names as the UR5e's); returns the
    sensor names."""
    spec.body(body).add_site(name=site, quat=list(quat), size=[0.005, 0.005, 0.005], group=4)
    for name, kind in (
        (FORCE_SENSOR, mujoco.mjtSensor.mjSENS_FORCE),
        (TORQUE_SENSOR, mujoco.mjtSensor.mjSENS_TORQUE),
    ):
        spec.add_sensor(name=name, type=kind, objtype=mujoco.mjtObj.mjOBJ_SITE, objname=site)
    return FORCE_SENSOR, TORQUE_SENSOR


def rendered_mesh_faces(model: mujoco.MjModel, groups: tuple[int, ...] = (0, 1, 2)) -> int:
    """Triangles the default cameras draw for mesh geoms (the render cost meshes.py bounds)."""
    faces = 0
    for geom_id in range(model.ngeom):
        is_mesh = model.geom_type[geom_id] == mujoco.mjtGeom.mjGEOM_MESH
        if is_mesh and model.geom_group[geom_id] in groups:
            faces += int(model.mesh_facenum[model.geom_dataid[geom_id]])
    return faces
