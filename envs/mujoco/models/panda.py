"""RMB's MuJoCo Franka Panda, from example-robot-data's ``panda.urdf`` (arm + hand).

Sources (RMB = RoboManipBaselines commit 8535948, paths under
``robo_manip_baselines/envs/``):

- model: example-robot-data ``panda_description/urdf/panda.urdf`` (franka_ros, Apache-2.0).
  Its kinematics and inertials are RMB's (``assets/mujoco/robots/panda/panda_body.xml``, the
  Menagerie Panda). Its visual meshes are COLLADA, which MuJoCo cannot read (the URDF importer
  drops ``<visual>``): what renders is the coarse collision STLs (2 300 triangles in all) and
  the fingers' boxes, so no mesh simplification is needed;
- joint damping 40 (joints 1-4), 2 (5-7), 10 (fingers) and armature 0.1: ``panda_body.xml``
  lines 21-119, ``panda_config.xml`` line 5 (the URDF's 0.003 damping and no armature let the
  15 g fingers blow through their limits);
- arm servos ``actuator1..7``: ``panda_config.xml`` lines 126-138 (kp, kv, ctrlrange); their
  force limit is +-100 N m for joints 1-4 (the ``<position forcerange>`` default of line 7
  overrides line 6's ``general`` +-87 for ``position`` actuators; measured by compiling RMB's
  defaults) and +-12 for joints 5-7;
- gripper: command 0..1 = finger opening 0..0.04 m, measured ``mean(fingers) / 0.04``
  (``mujoco/panda/MujocoPandaEnvBase.py`` line 106), RMB's ``actuator8`` as is
  (``panda_config.xml`` lines 139-140: gear 25 on finger_joint1, gain 10, bias
  (0, -10, -0.1), |force| <= 5) with the finger equality (line 122). On robotblockset's
  Menagerie fingers a step close tunnelled through a 3 cm cube (docs/robot-models.md); on these
  fingers it does not (measured: cube, 1 cm plate and the cable's 2 cm capsule held after a
  step close, cube picked and lifted in 12 poses, < 1 mm slip), and it holds the cable's
  capsule where Menagerie's tendon actuator (rescaled to 0..1, stiffened to 1000 N/m) let it
  drop: so RMB's is kept;
- fingertip contact: the rubber-tip boxes take RMB's ``fingertip_pad_collision_4`` contact
  parameters (``panda_config.xml`` line 30); the fingers' other boxes are render-only, as in
  RMB (lines 18-29); the finger equality takes RMB's softness (line 122);
- F/T site on the hand body (``panda_body.xml`` line 94); TCP between the fingertip pads
  (franka_ros ``panda_hand_tcp``, 0.1034 m from the hand); no hand camera (RMB has none);
- mount: ``assets/mujoco/envs/panda/env_panda_cable.xml`` line 36, ``panda_root_frame`` at
  (-0.5, 0, 0.8), stand line 33; home: ``mujoco/panda/MujocoPandaCableEnv.py`` lines 20-30,
  gripper open (``MujocoPandaEnvBase.py`` line 51).

Unlike RMB's Panda, whose arm links do not collide at all (``panda_config.xml`` line 16), the
links collide with the world through the URDF's collision meshes, as the UR5e's do; but not
with each other (RMB has no self-collision either, and the convex hulls MuJoCo collides meshes
with overlap in ordinary poses: link5's hull touched link7 or the hand in a third of 2000
random configurations).
"""

from __future__ import annotations

import mujoco

from rmb_lerobot.envs.mujoco.models.common import (
    ArmModel,
    RobotModel,
    StandBox,
    add_arm_servos,
    add_ft_sensor,
    add_servo,
    load_erd_urdf,
    mount,
)
from rmb_lerobot.envs.robots import Robot

URDF = "panda_description/urdf/panda.urdf"
BASE_BODY = "panda_link0"
ACTUATORS = tuple(f"actuator{i}" for i in range(1, 8))
GRIPPER_ACTUATOR = "actuator8"
RMB_STAND = StandBox(pos=(-0.5, 0.0, 0.4), half_size=(0.22, 0.22, 0.4))
# panda_config.xml lines 126-138: (kp, kv, |force|), force as explained in the module docstring.
_GAINS = ((1000, 20, 100),) * 2 + ((750, 4, 100),) * 2 + ((300, 2, 12),) * 3
_DAMPING = (40, 40, 40, 40, 2, 2, 2)  # panda_body.xml lines 21-83
# Contact bits: the robot's geoms hit anything of contype 1 (the default), never each other.
ROBOT_CONTYPE, ROBOT_CONAFFINITY = 2, 1
_WHITE, _OFF_WHITE, _BLACK = (1, 1, 1, 1), (0.901961, 0.921569, 0.929412, 1), (0.25, 0.25, 0.25, 1)


def _rename(spec: mujoco.MjSpec) -> None:
    """franka_ros joint names -> RMB's (``panda_joint1`` -> ``joint1``), equalities too."""
    names = {f"panda_joint{i}": f"joint{i}" for i in range(1, 8)}
    names |= {f"panda_finger_joint{i}": f"finger_joint{i}" for i in (1, 2)}
    for old, new in names.items():
        spec.joint(old).name = new
    for eq in spec.equalities:  # the URDF <mimic> is a joint equality naming both joints
        eq.name1, eq.name2 = names.get(eq.name1, eq.name1), names.get(eq.name2, eq.name2)


def _fingers(spec: mujoco.MjSpec) -> None:
    """RMB's finger contact: only the rubber tip collides, with the pad's softness."""
    for body_name in ("panda_leftfinger", "panda_rightfinger"):
        boxes = [g for g in spec.body(body_name).geoms if g.type == mujoco.mjtGeom.mjGEOM_BOX]
        # franka_ros order: screw mount, carriage sledge, diagonal finger, rubber tip.
        if len(boxes) != 4:
            raise ValueError(f"{URDF}: expected 4 boxes on {body_name}, found {len(boxes)}")
        for geom in boxes[:3]:
            geom.contype = geom.conaffinity = 0
            geom.group = 2
            geom.rgba = list(_BLACK)
        tip = boxes[3]
        tip.solimp = [0.95, 0.99, 0.001, 0.5, 2.0]
        tip.solref = [0.004, 1.0]
        tip.priority = 1
        tip.rgba = list(_BLACK)
    for eq in spec.equalities:
        eq.solimp = [0.95, 0.99, 0.001, 0.5, 2.0]
        eq.solref = [0.005, 1.0]


def build_panda(robot: Robot) -> RobotModel:
    """Panda + hand + wrist F/T sensor, base at the record's mount.

    Args:
        robot: The Panda record (:data:`rmb_lerobot.envs.robots.PANDA`): joints (RMB's names),
            gripper, home, frames and mount.

    Returns:
        The model, on RMB's stand.

    Raises:
        ValueError: If the record has no wrench frame (this model has a wrist F/T sensor).
    """
    (record,) = robot.arms
    if record.wrench_frame is None:
        raise ValueError(f"{robot.name}: the Panda model has a wrist F/T sensor")
    joints, gripper_joints, hand = record.joints, record.gripper.joints, record.hand_frame
    spec, _ = load_erd_urdf(URDF)
    spec.modelname = "panda"
    spec.option.timestep = 0.004  # env_panda_common.xml line 3
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.compiler.autolimits = True
    _rename(spec)
    for joint, damping in zip(joints, _DAMPING, strict=True):
        spec.joint(joint).damping = [damping, 0, 0]  # MuJoCo 4: damping is a 3-vector
    for joint in gripper_joints:
        spec.joint(joint).damping = [10, 0, 0]
    for joint in spec.joints:
        joint.armature = 0.1
    for body in spec.bodies:
        for geom in body.geoms:
            if geom.type == mujoco.mjtGeom.mjGEOM_MESH:
                geom.rgba = list(_OFF_WHITE if body.name == hand else _WHITE)
    _fingers(spec)
    for geom in spec.geoms:
        if geom.contype or geom.conaffinity:
            geom.contype, geom.conaffinity = ROBOT_CONTYPE, ROBOT_CONAFFINITY

    add_arm_servos(spec, joints, ACTUATORS, _GAINS)
    add_servo(  # panda_config.xml lines 139-140
        spec,
        GRIPPER_ACTUATOR,
        gripper_joints[0],
        kp=10.0,
        kv=0.1,
        gear=25.0,
        ctrl_range=record.gripper.command_range,
        force_range=(-5.0, 5.0),
    )
    spec.body("panda_link7").add_site(name=record.eef_frame, size=[0.005, 0, 0], group=4)
    spec.body(hand).add_site(name=record.tcp_frame, pos=[0, 0, 0.1034], size=[0.005, 0, 0], group=4)
    force, torque = add_ft_sensor(spec, hand, record.wrench_frame)
    mount(spec, BASE_BODY, record.root_frame, record.mount.pos, record.mount.quat)

    arm = ArmModel(
        record=record,
        arm_actuators=ACTUATORS,
        gripper_actuator=GRIPPER_ACTUATOR,
        base_body=BASE_BODY,
        force_sensor=force,
        torque_sensor=torque,
        hand_camera=None,
    )
    return RobotModel("panda", spec, (arm,), {}, stand=RMB_STAND)
