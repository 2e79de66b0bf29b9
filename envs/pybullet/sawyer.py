"""RMB's Sawyer + WSG50 + DIGIT arm for PyBullet, built in code.

RMB's TACTO envs load ``sawyer_wsg50.urdf`` (``RMB: robo_manip_baselines/envs/assets/tacto/robots/
sawyer/sawyer_wsg50.urdf``): a Rethink Sawyer 7-DoF arm, a Weiss WSG50 parallel gripper and two
DIGIT tactile sensors on the fingertips. No Sawyer or DIGIT model ships in a package we may depend
on, and model files are never copied from other repositories, so this module writes the URDF text
itself: RMB's kinematics (joint origins, axes, limits: re-typed facts), masses and inertias, and
RMB's collision primitives for the arm; visuals of the arm are primitives in Sawyer's colours. The
gripper base is pybullet_data's own ``gripper/meshes/WSG50_110.stl`` (byte-identical to RMB's,
referenced by absolute path); guides, finger adapters and the DIGIT bodies are boxes of the size of
RMB's meshes (their bounding boxes, read from RMB's STL files).

The DIGIT gel pad of each fingertip link (``finger_left_tip`` / ``finger_right_tip``, RMB's sensor
links) is a flat box face: its outward normal is the link frame's **+x** axis (:data:`PAD_NORMAL`),
its centre :data:`PAD_CENTRE`, its size :data:`PAD_SIZE` (0.02 m across = link y, 0.03 m along the
finger = link z, TACTO's DIGIT gel). The right finger's frames are turned by pi about z (RMB's
``base_joint_gripper_right`` origin), so at any opening the two pads face each other.

Placement: RMB asks pybulletX for the base at (0, 0, 0.1), but pybulletX re-places the base's
centre of mass there and RMB's ``base`` link carries an inertial origin of (-0.1, 0, 0.07), so the
robot's root frame sits at :data:`ROOT_POSITION` = (0.1, 0, 0.03) in RMB's worlds (at RMB's home
the gripper then hangs right over the Insert board at (0.505, -0.03)). :func:`load_sawyer_wsg50`
places it the same way.

Gripper sign: RMB commands the finger joints to ``(-g, +g)`` (``TactoSawyerEnvBase.py:305-314``);
both joints move their finger outwards as ``g`` grows, so a larger ``g`` opens the gripper. The
pad-to-pad gap is ``2 * (g + 0.006 - PAD_CENTRE[0])`` (each tip sits 0.006 m outside its finger's
axis): 0.012 m at RMB's home ``g = 0.02``, zero at ``g = 0.014`` (below that the pads would pass
through each other: like RMB, the robot has no self-collision).
"""

from __future__ import annotations

import hashlib
import math
import os
import tempfile
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from xml.sax.saxutils import quoteattr

import numpy as np
import pybullet as p
import pybullet_data

Vec3 = tuple[float, float, float]
Rgba = tuple[float, float, float, float]

# --------------------------------------------------------------------------- RMB's names / values
#: Arm joints in RMB's order (``RMB: envs/tacto/TactoSawyerEnvBase.py:317-325``).
ARM_JOINT_NAMES: tuple[str, ...] = tuple(f"right_j{i}" for i in range(7))
#: Prismatic finger joints, left then right (``TactoSawyerEnvBase.py:326-329``).
FINGER_JOINT_NAMES: tuple[str, str] = ("base_joint_gripper_left", "base_joint_gripper_right")
#: The DIGIT sensor links (children of ``FINGERTIP_JOINT_NAMES``), left then right.
FINGERTIP_LINK_NAMES: tuple[str, str] = ("finger_left_tip", "finger_right_tip")
#: The fixed joints RMB names when it addresses the sensor links (``TactoSawyerEnvBase.py:211``).
FINGERTIP_JOINT_NAMES: tuple[str, str] = ("joint_finger_tip_left", "joint_finger_tip_right")
#: Fixed joint carrying the F/T sensor; RMB's wrench is its reaction force (lines 207-209, 351).
FT_JOINT_NAME = "right_hand"
#: RMB's end-effector: Pinocchio joint 7 (``ik_eef_joint_id=7``) of ``sawyer.urdf``, i.e. the
#: ``right_j6`` joint frame = the ``right_l6`` link frame (``TactoSawyerEnvBase.py:193-205``).
EEF_LINK_NAME = "right_l6"
#: Root link of the URDF (the robot base frame FK/IK poses refer to).
BASE_LINK_NAME = "base"

#: Where RMB asks for the base (``px.Robot(base_position=[0, 0, 0.1])``, line 188). pybulletX
#: loads the URDF there and then calls ``resetBasePositionAndOrientation`` with the same position
#: (``pybulletX: body.py``), which places the base's *centre of mass* there: RMB's ``base`` link
#: has its inertial origin at :data:`BASE_INERTIAL_XYZ`, so its link frame (the robot's root
#: frame) ends up at :data:`ROOT_POSITION`. :func:`load_sawyer_wsg50` does the same.
BASE_POSITION: Vec3 = (0.0, 0.0, 0.1)
#: RMB's inertial origin of the massless ``base`` link (``sawyer_wsg50.urdf:30``).
BASE_INERTIAL_XYZ: Vec3 = (-0.1, 0.0, 0.07)


def root_position(base_position: Sequence[float] = BASE_POSITION) -> Vec3:
    """World position of the URDF root link frame when the base is placed RMB's way.

    Args:
        base_position: The position given to :func:`load_sawyer_wsg50` (pybullet's base = the
            base link's centre of mass).

    Returns:
        ``base_position - BASE_INERTIAL_XYZ`` (the root frame is not rotated).
    """
    x, y, z = (float(b) - float(o) for b, o in zip(base_position, BASE_INERTIAL_XYZ, strict=True))
    return (round(x, 12), round(y, 12), round(z, 12))


#: Where RMB's robot root frame really is in the world of the TACTO envs: (0.1, 0, 0.03).
ROOT_POSITION: Vec3 = root_position(BASE_POSITION)
#: RMB's home pose of the arm (``TactoSawyerGraspEnv.py:16-28``, also Insert's).
HOME_ARM_QPOS: tuple[float, ...] = (0.0, -1.24, -0.58, 2.18, 0.27, 0.7, 1.0)
#: RMB's home gripper value ``g``: fingers at ``(-g, +g)``.
HOME_GRIPPER = 0.02
HOME_FINGER_QPOS: tuple[float, float] = (-HOME_GRIPPER, HOME_GRIPPER)

#: Max motor forces of RMB's position control (``TactoSawyerEnvBase.py:310-311``).
ARM_MAX_FORCE = 200.0
FINGER_MAX_FORCE = 20.0

#: ``p.changeDynamics`` keyword arguments for both sensor links: RMB's frictions (lines
#: 211-221), a stiffer contact than RMB's (300 N/m, damping 30). With RMB's, a 20 N grasp of
#: Grasp's box sank it 10 mm into each 4 mm pad (the pads closed to 9.4 mm on a 30 mm box), so
#: nothing lay in front of the gel for the tactile rays to see; at 10000 / 200 it sinks 0.5 mm,
#: the grasp still succeeds, and the DIGIT image carries the press (measured, Grasp seed 0).
FINGERTIP_DYNAMICS = MappingProxyType(
    {
        "lateralFriction": 1.2,
        "spinningFriction": 0.03,
        "rollingFriction": 0.03,
        "contactStiffness": 10000.0,
        "contactDamping": 200.0,
    }
)

# --------------------------------------------------------------------------- DIGIT pad geometry
#: Outward normal of the gel pad in its fingertip link frame (the link's +x axis, as TACTO's DIGIT
#: camera looks along +x: ``tacto/config_digit.yml``).
PAD_NORMAL: Vec3 = (1.0, 0.0, 0.0)
#: Centre of the pad's contact face in the fingertip link frame. x is where RMB's ``digit.STL``
#: collision mesh ends (0.0201 m); z is TACTO's camera/gel height (0.015 m). TACTO renders its
#: curved gel at x 0.022 (``config_digit.yml`` ``gel.origin``), a few mm in front of the face.
PAD_CENTRE: Vec3 = (0.020, 0.0, 0.015)
#: Pad face size: (across the finger = link y, along the finger = link z), TACTO's DIGIT gel.
PAD_SIZE: tuple[float, float] = (0.02, 0.03)
#: Thickness of the pad box behind the face (the rest of the DIGIT body is the housing box).
PAD_THICKNESS = 0.004

#: Midpoint of the two pad centres in the eef (``right_l6``) frame at any opening: the gripper
#: axis is the eef z axis (``right_hand`` 0.0245 + finger 0.023 + tip 0.08 + pad 0.015).
TOOL_CENTRE_IN_EEF: Vec3 = (0.0, 0.0, 0.1425)

URDF_FILE_NAME = "sawyer_wsg50.urdf"
WSG50_MESH = "gripper/meshes/WSG50_110.stl"

# Colours: RMB's materials (``sawyer_red``, ``darkgray``) and the gripper's grey / white.
SAWYER_RED: Rgba = (0.5, 0.1, 0.1, 1.0)
DARK_GREY: Rgba = (0.2, 0.2, 0.2, 1.0)
GRIPPER_GREY: Rgba = (0.5, 0.5, 0.5, 1.0)
WHITE: Rgba = (1.0, 1.0, 1.0, 1.0)
GEL_GREY: Rgba = (0.8, 0.82, 0.85, 1.0)

# Tiny inertial for frame-only links (RMB's value for ``torso`` / ``*_itb``).
_FRAME_MASS = 1e-4
_FRAME_INERTIA = (1e-8, 0.0, 0.0, 1e-8, 0.0, 1e-8)


# --------------------------------------------------------------------------- model description
@dataclass(frozen=True)
class Shape:
    """One primitive (or mesh) of a link, placed in the link frame.

    ``kind`` is ``box`` (``size`` = 3 edge lengths), ``cylinder`` (``size`` = radius, length; the
    axis is the shape's z), ``sphere`` (``size`` = radius,) or ``mesh`` (``mesh`` path, ``size`` =
    scale xyz).
    """

    kind: str
    size: tuple[float, ...]
    xyz: Vec3 = (0.0, 0.0, 0.0)
    rpy: Vec3 = (0.0, 0.0, 0.0)
    rgba: Rgba | None = None
    mesh: str | None = None


@dataclass(frozen=True)
class Inertial:
    """Mass, centre of mass and inertia (ixx, ixy, ixz, iyy, iyz, izz) of a link."""

    mass: float
    xyz: Vec3 = (0.0, 0.0, 0.0)
    inertia: tuple[float, float, float, float, float, float] = _FRAME_INERTIA


@dataclass(frozen=True)
class LinkSpec:
    """A URDF link: inertial, visual and collision shapes, optional ``<contact>`` block."""

    name: str
    inertial: Inertial
    visuals: tuple[Shape, ...] = ()
    collisions: tuple[Shape, ...] = ()
    contact: tuple[tuple[str, float], ...] = ()


@dataclass(frozen=True)
class JointSpec:
    """A URDF joint with RMB's origin, axis, limits and dynamics."""

    name: str
    kind: str
    parent: str
    child: str
    xyz: Vec3 = (0.0, 0.0, 0.0)
    rpy: Vec3 = (0.0, 0.0, 0.0)
    axis: Vec3 | None = None
    limit: tuple[float, float, float, float] | None = None  # lower, upper, effort, velocity
    dynamics: tuple[float, float] | None = None  # damping, friction


@dataclass(frozen=True)
class SawyerHandles:
    """Indices of a loaded Sawyer + WSG50 body in one pybullet client.

    Joint and link indices coincide in pybullet (a link's index is that of its parent joint).
    """

    body_id: int
    arm_joints: tuple[int, ...]
    finger_joints: tuple[int, int]
    fingertip_links: tuple[int, int]
    eef_link: int
    ft_joint: int
    arm_lower: np.ndarray = field(repr=False)
    arm_upper: np.ndarray = field(repr=False)
    root_position: np.ndarray = field(repr=False)  # world position of the root frame

    @property
    def controlled_joints(self) -> tuple[int, ...]:
        """Arm joints then fingers: the order of RMB's ``[q7, -g, +g]`` command."""
        return self.arm_joints + self.finger_joints


# --------------------------------------------------------------------------- RMB's joint table
# Every origin, axis and limit below is re-typed from RMB's sawyer_wsg50.urdf (line numbers there).
# RMB writes pi/2 as 1.5708 and pi as 3.1416 / 3.14159: kept, so FK matches RMB's model exactly.
JOINTS: tuple[JointSpec, ...] = (
    JointSpec("torso_t0", "fixed", "base", "torso"),  # 101
    JointSpec("pedestal_fixed", "fixed", "base", "pedestal"),  # 106
    JointSpec("right_arm_mount", "fixed", "base", "right_arm_base_link"),  # 111
    JointSpec(  # 156
        "right_j0", "revolute", "right_arm_base_link", "right_l0",
        xyz=(0, 0, 0.08), axis=(0, 0, 1), limit=(-3.0503, 3.0503, 80, 1.74),
    ),
    JointSpec("head_pan", "fixed", "right_l0", "head", xyz=(0, 0, 0.2965)),  # 183
    JointSpec(  # 197
        "right_torso_itb", "fixed", "right_l0", "right_torso_itb",
        xyz=(-0.055, 0, 0.22), rpy=(0, -1.5708, 0),
    ),
    JointSpec(  # 223
        "right_j1", "revolute", "right_l0", "right_l1",
        xyz=(0.081, 0.05, 0.237), rpy=(-1.5708, 1.5708, 0), axis=(0, 0, 1),
        limit=(-3.8183, 2.2824, 80, 1.328),
    ),
    JointSpec(  # 250
        "right_j2", "revolute", "right_l1", "right_l2",
        xyz=(0, -0.14, 0.1425), rpy=(1.5708, 0, 0), axis=(0, 0, 1),
        limit=(-3.0514, 3.0514, 40, 1.957),
    ),
    JointSpec(  # 277
        "right_j3", "revolute", "right_l2", "right_l3",
        xyz=(0, -0.042, 0.26), rpy=(-1.5708, 0, 0), axis=(0, 0, 1),
        limit=(-3.0514, 3.0514, 40, 1.957),
    ),
    JointSpec(  # 304
        "right_j4", "revolute", "right_l3", "right_l4",
        xyz=(0, -0.125, -0.1265), rpy=(1.5708, 0, 0), axis=(0, 0, 1),
        limit=(-2.9842, 2.9842, 9, 3.485),
    ),
    JointSpec(  # 318
        "right_arm_itb", "fixed", "right_l4", "right_arm_itb",
        xyz=(-0.055, 0, 0.075), rpy=(0, -1.5708, 0),
    ),
    JointSpec(  # 344
        "right_j5", "revolute", "right_l4", "right_l5",
        xyz=(0, 0.031, 0.275), rpy=(-1.5708, 0, 0), axis=(0, 0, 1),
        limit=(-2.9842, 2.9842, 9, 3.485),
    ),
    JointSpec(  # 352
        "right_hand_camera", "fixed", "right_l5", "right_hand_camera",
        xyz=(0.039552, -0.033, 0.0695), rpy=(0, 1.5708, 0),
    ),
    JointSpec(  # 359
        "right_wrist", "fixed", "right_l5", "right_wrist", xyz=(0, 0, 0.10541), rpy=(1.5708, 0, 0)
    ),
    JointSpec(  # 385
        "right_j6", "revolute", "right_l5", "right_l6",
        xyz=(0, -0.11, 0.1053), rpy=(-1.5708, -0.17453, 3.1416), axis=(0, 0, 1),
        limit=(-4.7104, 4.7104, 9, 4.545),
    ),
    JointSpec(  # 405
        "right_hand", "fixed", "right_l6", "right_hand", xyz=(0, 0, 0.0245), rpy=(0, 0, 1.5708)
    ),
    JointSpec(  # 431
        "display_joint", "fixed", "head", "screen", xyz=(0.03, 0, 0.105), rpy=(1.5708, 0, 1.5708)
    ),
    JointSpec(  # 437
        "head_camera", "fixed", "head", "head_camera",
        xyz=(0.022803, 0, 0.21657), rpy=(-2.1293, 0, -1.5708),
    ),
    JointSpec(  # 499: the first <limit> (effort 1, velocity 1) is the one URDF parsers read
        "base_joint_gripper_left", "prismatic", "gripper_base_link", "gripper_left",
        axis=(1, 0, 0), limit=(-0.055, -0.0027, 1.0, 1.0), dynamics=(70.0, 100.0),
    ),
    JointSpec(  # 553
        "guide_joint_finger_left", "fixed", "gripper_left", "finger_left", xyz=(0, 0, 0.023)
    ),
    JointSpec(  # 603
        "joint_finger_tip_left", "fixed", "finger_left", "finger_left_tip", xyz=(-0.006, 0, 0.08)
    ),
    JointSpec(  # 648
        "base_joint_gripper_right", "prismatic", "gripper_base_link", "gripper_right",
        rpy=(0, 0, 3.14159), axis=(-1, 0, 0), limit=(0.0027, 0.055, 1.0, 1.0),
        dynamics=(70.0, 100.0),
    ),
    JointSpec(  # 701
        "guide_joint_finger_right", "fixed", "gripper_right", "finger_right", xyz=(0, 0, 0.023)
    ),
    JointSpec(  # 745
        "joint_finger_tip_right", "fixed", "finger_right", "finger_right_tip",
        xyz=(-0.006, 0, 0.08),
    ),
    JointSpec(  # 791
        "arm_gripper_joint", "fixed", "right_hand", "gripper_base_link", rpy=(0, 0, 1.5708)
    ),
)  # fmt: skip


# --------------------------------------------------------------------------- geometry helpers
def _box_inertia(mass: float, size: Sequence[float]) -> tuple[float, ...]:
    """Inertia of a solid box about its centre: a sensible tensor where RMB's (1.0) is not."""
    x, y, z = size
    k = mass / 12.0
    return (k * (y * y + z * z), 0.0, 0.0, k * (x * x + z * z), 0.0, k * (x * x + y * y))


def _span_box(lo: Vec3, hi: Vec3, rgba: Rgba | None = None) -> Shape:
    """A box spanning the corners ``lo``..``hi`` (how RMB's mesh bounding boxes are typed)."""
    size = tuple(round(h - low, 6) for low, h in zip(lo, hi, strict=True))
    centre = tuple(round((h + low) / 2.0, 6) for low, h in zip(lo, hi, strict=True))
    return Shape("box", size, xyz=centre, rgba=rgba)


def _rpy_z_to(direction: np.ndarray) -> Vec3:
    """Roll/pitch/yaw turning the z axis onto ``direction`` (to lay a cylinder along a bone)."""
    d = direction / np.linalg.norm(direction)
    pitch = math.atan2(math.hypot(d[0], d[1]), d[2])
    yaw = math.atan2(d[1], d[0]) if math.hypot(d[0], d[1]) > 1e-12 else 0.0
    return (0.0, round(pitch, 6), round(yaw, 6))


def _bone(start: Vec3, end: Vec3, radius: float, rgba: Rgba = SAWYER_RED) -> Shape:
    """A visual cylinder from ``start`` to ``end`` (link frame): a limb segment of the arm."""
    a, b = np.asarray(start, dtype=float), np.asarray(end, dtype=float)
    centre = tuple(round(float(v), 6) for v in (a + b) / 2.0)
    length = round(float(np.linalg.norm(b - a)), 6)
    return Shape("cylinder", (radius, length), xyz=centre, rpy=_rpy_z_to(b - a), rgba=rgba)


def _drum(radius: float, length: float, xyz: Vec3 = (0.0, 0.0, 0.0)) -> Shape:
    """A dark grey visual cylinder along the link's z axis: the joint housing at its origin."""
    return Shape("cylinder", (radius, length), xyz=xyz, rgba=DARK_GREY)


def _painted(shape: Shape, rgba: Rgba) -> Shape:
    """The same primitive as a visual of colour ``rgba`` (collision shapes have none)."""
    return Shape(shape.kind, shape.size, shape.xyz, shape.rpy, rgba, shape.mesh)


# --------------------------------------------------------------------------- links
# RMB's arm collision primitives (sawyer_wsg50.urdf lines in comments).
_COLLISION = {
    "pedestal": Shape("cylinder", (0.18, 0.62), xyz=(0, 0, -0.3)),  # 61-66
    "right_arm_base_link": Shape("cylinder", (0.08, 0.24), xyz=(0, 0, 0.12)),  # 129-134
    "right_l0": Shape("sphere", (0.07,), xyz=(0.081, 0, 0.237)),  # 149-154
    "head": Shape("sphere", (0.18,), xyz=(0, 0, 0.08)),  # 176-181
    "right_l1": Shape("sphere", (0.07,), xyz=(0, 0, 0.1225)),  # 216-221
    "right_l2": Shape("cylinder", (0.06, 0.35), xyz=(0, 0, 0.14)),  # 243-248
    "right_l3": Shape("sphere", (0.06,), xyz=(0, -0.01, -0.12)),  # 270-275
    "right_l4": Shape("cylinder", (0.045, 0.36), xyz=(0, 0, 0.14)),  # 297-302
    "right_l5": Shape("sphere", (0.06,), xyz=(0.01, 0, 0.09)),  # 337-342
    "right_l6": Shape("cylinder", (0.065, 0.05), xyz=(0, 0, -0.005)),  # 378-383
    "screen": Shape("sphere", (0.001,), xyz=(0, 0, 0)),  # 419-424
}

# RMB's arm inertials: mass, centre of mass, (ixx, ixy, ixz, iyy, iyz, izz).
_INERTIAL = {
    "base": Inertial(0.0, (-0.1, 0, 0.07), (0.05, 0, 0, 0.06, 0, 0.03)),
    "torso": Inertial(_FRAME_MASS),
    "pedestal": Inertial(60.864, (0, 0, 0), (5.0636, 0.0010342, 0.802, 6.0869, 0.0010531, 4.9619)),
    "right_arm_base_link": Inertial(
        2.0687,
        (-0.0006241, -2.8025e-05, 0.065404),
        (0.0067599, -4.2024e-05, -6.1904e-07, 0.0067877, 1.5888e-05, 0.0074031),
    ),
    "right_l0": Inertial(
        5.3213,
        (0.024366, 0.010969, 0.14363),
        (0.053314, 0.0047093, 0.011734, 0.057902, 0.0080179, 0.023659),
    ),
    "head": Inertial(
        1.5795,
        (0.0053207, -2.6549e-05, 0.1021),
        (0.011833, -4.4669e-06, 4.9425e-05, 0.0082709, 4.2124e-07, 0.0049661),
    ),
    "right_torso_itb": Inertial(_FRAME_MASS),
    "right_l1": Inertial(
        4.505,
        (-0.0030849, -0.026811, 0.092521),
        (0.022398, -0.00023986, -0.00029362, 0.014613, -0.0060875, 0.017295),
    ),
    "right_l2": Inertial(
        1.7251,
        (-0.00016232, -0.015346, 0.13445),
        (0.025176, 4.3031e-06, 1.4564e-05, 0.024982, -0.0033928, 0.0033798),
    ),
    "right_l3": Inertial(
        2.4743,
        (-0.0046678, -0.028394, -0.083127),
        (0.0099549, -1.7675e-05, 0.00027521, 0.0064248, 0.0030853, 0.0067746),
    ),
    "right_l4": Inertial(
        1.0433,
        (-0.0027794, 0.0076558, 0.13273),
        (0.012913, 2.573e-05, 0.00017705, 0.012939, 0.0011152, 0.0012405),
    ),
    "right_arm_itb": Inertial(_FRAME_MASS),
    "right_l5": Inertial(
        1.5343,
        (0.0062067, -0.024291, 0.075564),
        (0.0046072, 0.00012002, 5.3065e-05, 0.0028725, -0.0011886, 0.003101),
    ),
    "right_l6": Inertial(
        0.3292,
        (-8.0726e-06, 0.0085838, -0.0049566),
        (0.00031105, 1.4771e-06, -3.7074e-07, 0.00021549, -8.4533e-06, 0.00035976),
    ),
    # RMB: mass 1e-8 with every inertia entry 1e-8 (a singular tensor); kept diagonal here.
    "right_hand": Inertial(1e-8, (0, 0, 0), (1e-8, 0, 0, 1e-8, 0, 1e-8)),
    "screen": Inertial(_FRAME_MASS),
}

# The WSG50's parts as boxes of the bounding boxes of RMB's meshes (m, in each link's frame).
#: ``GUIDE_WSG50_110.stl`` x 0.001 in ``gripper_left`` / ``gripper_right``.
GUIDE_BOX: tuple[Vec3, Vec3] = ((-0.018, -0.015, 0.0594), (0.0, 0.015, 0.0965))
#: ``DIGIT-WSG-50-V1.STL`` x 0.001 at (0.003, 0.015, 0.057) rpy (1.57, 0, -1.57) in ``finger_*``.
FINGER_BOX: tuple[Vec3, Vec3] = ((-0.018, -0.015, 0.057), (0.003, 0.015, 0.08))
#: ``digit.STL`` without its gel, in ``finger_*_tip`` (the pad box sits on its +x face).
DIGIT_HOUSING_BOX: tuple[Vec3, Vec3] = (
    (-0.0122, -0.0135, 0.0),
    (PAD_CENTRE[0] - PAD_THICKNESS, 0.0135, 0.0346),
)
_GRIPPER_BASE_MASS = 1.2  # RMB, line 463
_GRIPPER_PART_MASS = 0.1  # RMB: every guide, finger and tip
_WSG50_BASE_SIZE: Vec3 = (0.146, 0.05, 0.0725)  # WSG50_110.stl's extent (RMB's comment: a box)
_FINGER_CONTACT = (  # RMB's <contact> of finger_* and finger_*_tip (lines 564-569)
    ("lateral_friction", 1.0),
    ("rolling_friction", 0.1),
    ("contact_cfm", 0.0),
    ("contact_erp", 1.0),
)


def pad_box() -> Shape:
    """The DIGIT gel pad of a fingertip link: a box whose +x face is the contact face."""
    lo = (PAD_CENTRE[0] - PAD_THICKNESS, -PAD_SIZE[0] / 2, PAD_CENTRE[2] - PAD_SIZE[1] / 2)
    hi = (PAD_CENTRE[0], PAD_SIZE[0] / 2, PAD_CENTRE[2] + PAD_SIZE[1] / 2)
    return _span_box(lo, hi)


def _arm_visuals() -> dict[str, tuple[Shape, ...]]:
    """Sawyer-like primitives: red limbs along the kinematic chain, dark grey joint drums."""
    col = _COLLISION
    return {
        "pedestal": (_painted(col["pedestal"], DARK_GREY),),
        "right_arm_base_link": (_drum(0.09, 0.08, (0, 0, 0.04)),),
        "right_l0": (
            _bone((0, 0, 0.04), (0, 0, 0.237), 0.075),
            _bone((0, 0, 0.237), (0.081, 0, 0.237), 0.07),
            _painted(col["right_l0"], SAWYER_RED),
        ),
        "head": (
            _bone((0, 0, 0.0), (0, 0, 0.04), 0.03, DARK_GREY),
            Shape("box", (0.058, 0.26, 0.16), xyz=(0, 0, 0.105), rgba=SAWYER_RED),
        ),
        "right_l1": (
            _drum(0.072, 0.1, (0, 0, 0.05)),
            _bone((0, 0, 0.1), (0, 0, 0.1425), 0.07),
            _bone((0, 0, 0.1425), (0, -0.1, 0.1425), 0.065),
        ),
        "right_l2": (
            _drum(0.062, 0.06, (0, 0, -0.03)),
            _bone((0, 0, 0.0), (0, 0, 0.26), 0.06),
            _bone((0, 0, 0.26), (0, -0.042, 0.26), 0.055),
        ),
        "right_l3": (
            _drum(0.06, 0.1, (0, 0, -0.02)),
            _bone((0, 0, -0.02), (0, 0, -0.1265), 0.055),
            _bone((0, 0, -0.1265), (0, -0.09, -0.1265), 0.05),
        ),
        "right_l4": (
            _drum(0.05, 0.06, (0, 0, -0.03)),
            _bone((0, 0, 0.0), (0, 0, 0.275), 0.045),
            _bone((0, 0, 0.275), (0, 0.031, 0.275), 0.045),
        ),
        "right_l5": (
            _drum(0.05, 0.08, (0, 0, 0.0)),
            _bone((0, 0, 0.04), (0, 0, 0.1053), 0.048),
            _bone((0, 0, 0.1053), (0, -0.08, 0.1053), 0.045),
        ),
        "right_l6": (_painted(col["right_l6"], DARK_GREY),),
        "screen": (Shape("box", (0.24, 0.14, 0.002), rgba=DARK_GREY),),  # RMB's own box
    }


def _arm_links() -> list[LinkSpec]:
    """The Sawyer's links: RMB's inertials and collision primitives, primitive visuals."""
    visuals = _arm_visuals()
    names = (
        "base", "torso", "pedestal", "right_arm_base_link", "right_l0", "head",
        "right_torso_itb", "right_l1", "right_l2", "right_l3", "right_l4", "right_arm_itb",
        "right_l5", "right_hand_camera", "right_wrist", "right_l6", "right_hand", "screen",
        "head_camera",
    )  # fmt: skip
    return [
        LinkSpec(
            name,
            # RMB gives right_hand_camera / right_wrist / head_camera no <inertial>; pybullet
            # would then make each a 1 kg link: a frame-only link gets a tiny mass instead.
            _INERTIAL.get(name, Inertial(_FRAME_MASS)),
            visuals.get(name, ()),
            (_COLLISION[name],) if name in _COLLISION else (),
        )
        for name in names
    ]


def _gripper_links(mesh_path: str) -> list[LinkSpec]:
    """The WSG50 base (pybullet_data's mesh), guides, finger adapters and DIGIT fingertips."""
    base_mesh = Shape("mesh", (1.0, 1.0, 1.0), mesh=mesh_path)  # RMB's scale 1 (line 474)
    links = [
        LinkSpec(
            "gripper_base_link",
            Inertial(
                _GRIPPER_BASE_MASS, inertia=_box_inertia(_GRIPPER_BASE_MASS, _WSG50_BASE_SIZE)
            ),
            (_painted(base_mesh, GRIPPER_GREY),),
            (base_mesh,),
        )
    ]
    guide = _span_box(*GUIDE_BOX)
    finger = _span_box(*FINGER_BOX)
    housing = _span_box(*DIGIT_HOUSING_BOX)
    pad = pad_box()
    for side in ("left", "right"):
        links += [
            LinkSpec(
                f"gripper_{side}",
                Inertial(
                    _GRIPPER_PART_MASS, guide.xyz, _box_inertia(_GRIPPER_PART_MASS, guide.size)
                ),
                (_painted(guide, WHITE),),
                (guide,),
            ),
            LinkSpec(
                f"finger_{side}",
                Inertial(
                    _GRIPPER_PART_MASS, finger.xyz, _box_inertia(_GRIPPER_PART_MASS, finger.size)
                ),
                (_painted(finger, WHITE),),
                (finger,),
                _FINGER_CONTACT,
            ),
            LinkSpec(
                f"finger_{side}_tip",
                Inertial(
                    _GRIPPER_PART_MASS, housing.xyz, _box_inertia(_GRIPPER_PART_MASS, housing.size)
                ),
                (_painted(housing, DARK_GREY), _painted(pad, GEL_GREY)),
                (housing, pad),
                _FINGER_CONTACT,
            ),
        ]
    return links


# --------------------------------------------------------------------------- URDF text
def _num(value: float) -> str:
    """Deterministic, short number text (``1.5708``, ``2.8025e-05``, ``0``)."""
    text = format(float(value), ".10g")
    return "0" if text == "-0" else text


def _nums(values: Iterable[float]) -> str:
    return " ".join(_num(v) for v in values)


def _origin(xyz: Sequence[float], rpy: Sequence[float]) -> str:
    return f'<origin xyz="{_nums(xyz)}" rpy="{_nums(rpy)}"/>'


def _geometry(shape: Shape) -> str:
    if shape.kind == "box":
        return f'<box size="{_nums(shape.size)}"/>'
    if shape.kind == "cylinder":
        radius, length = shape.size
        return f'<cylinder radius="{_num(radius)}" length="{_num(length)}"/>'
    if shape.kind == "sphere":
        return f'<sphere radius="{_num(shape.size[0])}"/>'
    if shape.kind == "mesh":
        return f"<mesh filename={quoteattr(str(shape.mesh))} scale={quoteattr(_nums(shape.size))}/>"
    raise ValueError(f"unknown shape kind {shape.kind!r}")


def _shape_xml(tag: str, shape: Shape) -> list[str]:
    lines = [f"    <{tag}>", f"      {_origin(shape.xyz, shape.rpy)}"]
    lines.append(f"      <geometry>{_geometry(shape)}</geometry>")
    if tag == "visual" and shape.rgba is not None:
        # pybullet ignores an unnamed material: name each colour after its rgba.
        name = "rgba_" + "_".join(_num(v) for v in shape.rgba)
        lines.append(
            f'      <material name="{name}"><color rgba="{_nums(shape.rgba)}"/></material>'
        )
    lines.append(f"    </{tag}>")
    return lines


def _link_xml(link: LinkSpec) -> list[str]:
    ixx, ixy, ixz, iyy, iyz, izz = link.inertial.inertia
    lines = [f'  <link name="{link.name}">']
    if link.contact:
        lines.append("    <contact>")
        lines += [f'      <{key} value="{_num(value)}"/>' for key, value in link.contact]
        lines.append("    </contact>")
    lines += [
        "    <inertial>",
        f"      {_origin(link.inertial.xyz, (0, 0, 0))}",
        f'      <mass value="{_num(link.inertial.mass)}"/>',
        f'      <inertia ixx="{_num(ixx)}" ixy="{_num(ixy)}" ixz="{_num(ixz)}" '
        f'iyy="{_num(iyy)}" iyz="{_num(iyz)}" izz="{_num(izz)}"/>',
        "    </inertial>",
    ]
    for shape in link.visuals:
        lines += _shape_xml("visual", shape)
    for shape in link.collisions:
        lines += _shape_xml("collision", shape)
    lines.append("  </link>")
    return lines


def _joint_xml(joint: JointSpec) -> list[str]:
    lines = [
        f'  <joint name="{joint.name}" type="{joint.kind}">',
        f'    <parent link="{joint.parent}"/>',
        f'    <child link="{joint.child}"/>',
        f"    {_origin(joint.xyz, joint.rpy)}",
    ]
    if joint.axis is not None:
        lines.append(f'    <axis xyz="{_nums(joint.axis)}"/>')
    if joint.limit is not None:
        lower, upper, effort, velocity = joint.limit
        lines.append(
            f'    <limit lower="{_num(lower)}" upper="{_num(upper)}" '
            f'effort="{_num(effort)}" velocity="{_num(velocity)}"/>'
        )
    if joint.dynamics is not None:
        damping, friction = joint.dynamics
        lines.append(f'    <dynamics damping="{_num(damping)}" friction="{_num(friction)}"/>')
    lines.append("  </joint>")
    return lines


def wsg50_mesh_path() -> Path:
    """Absolute path of pybullet_data's ``WSG50_110.stl`` (byte-identical to RMB's)."""
    return Path(pybullet_data.getDataPath()) / WSG50_MESH


def sawyer_wsg50_urdf() -> str:
    """The URDF text of RMB's Sawyer + WSG50 + DIGIT robot (deterministic for one install).

    Returns:
        The URDF document. The only file it names is pybullet_data's ``WSG50_110.stl`` (absolute
        path), so the text loads from any directory.
    """
    links = _arm_links() + _gripper_links(str(wsg50_mesh_path()))
    lines = [
        '<?xml version="1.0"?>',
        "<!-- Generated by rmb_lerobot.envs.pybullet.sawyer: RMB's Sawyer + WSG50 + DIGIT",
        "     kinematics (sawyer_wsg50.urdf), geometry built from primitives. -->",
        '<robot name="sawyer">',
    ]
    for link in links:
        lines += _link_xml(link)
    for joint in JOINTS:
        lines += _joint_xml(joint)
    lines.append("</robot>")
    return "\n".join(lines) + "\n"


def write_sawyer_wsg50_urdf(directory: Path) -> Path:
    """Write :func:`sawyer_wsg50_urdf` to ``directory/sawyer_wsg50.urdf``.

    The file is written to a temporary file beside it and moved into place, so a concurrent
    reader (another process loading the same cache directory) never sees a partial file.

    Args:
        directory: Where to write; created if missing.

    Returns:
        The path of the URDF file.
    """
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    target = directory / URDF_FILE_NAME
    text = sawyer_wsg50_urdf()
    fd, tmp = tempfile.mkstemp(prefix=".sawyer_wsg50-", suffix=".tmp", dir=directory)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as handle:
            handle.write(text)
        os.replace(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return target


def default_urdf_directory() -> Path:
    """A per-content cache directory under the system temp dir for the generated URDF.

    The directory name carries a hash of the text, so a changed model (or another pybullet_data
    location) never reuses a stale file.
    """
    digest = hashlib.sha256(sawyer_wsg50_urdf().encode("utf-8")).hexdigest()[:16]
    return Path(tempfile.gettempdir()) / "rmb_lerobot" / f"sawyer_wsg50-{digest}"


# --------------------------------------------------------------------------- loading
def joint_indices_by_name(body_id: int, client_id: int) -> dict[str, int]:
    """Map every joint name of a body to its pybullet index (= its child link's index)."""
    return {
        p.getJointInfo(body_id, i, physicsClientId=client_id)[1].decode(): i
        for i in range(p.getNumJoints(body_id, physicsClientId=client_id))
    }


def link_indices_by_name(body_id: int, client_id: int) -> dict[str, int]:
    """Map every link name of a body to its pybullet index (the base link is -1)."""
    names = {
        p.getJointInfo(body_id, i, physicsClientId=client_id)[12].decode(): i
        for i in range(p.getNumJoints(body_id, physicsClientId=client_id))
    }
    names[p.getBodyInfo(body_id, physicsClientId=client_id)[0].decode()] = -1
    return names


def load_sawyer_wsg50(
    client_id: int,
    *,
    directory: Path | None = None,
    base_position: Sequence[float] = BASE_POSITION,
) -> SawyerHandles:
    """Load the robot into a pybullet client the way RMB's TACTO envs do.

    Fixed base placed like pybulletX's ``Body`` (``loadURDF`` at ``base_position``, then
    ``resetBasePositionAndOrientation`` to it, which moves the base's centre of mass there: the
    root frame lands at :func:`root_position`, (0.1, 0, 0.03) for RMB's (0, 0, 0.1)). No
    self-collision and no flags (as RMB, so pybullet recomputes the inertia tensors from the
    collision shapes, as in RMB), RMB's contact dynamics on the two sensor links, the F/T sensor
    of ``right_hand`` enabled. Joints start at zero; set RMB's home with :func:`reset_joints`.

    Args:
        client_id: The pybullet physics client.
        directory: Where to write the URDF; a content-hashed temp directory by default.
        base_position: pybullet's base position (the base link's centre of mass), RMB's value
            by default.

    Returns:
        The body id and the indices the env needs.

    Raises:
        KeyError: If the generated model lacks one of RMB's names (a bug in this module).
    """
    path = write_sawyer_wsg50_urdf(directory or default_urdf_directory())
    body = p.loadURDF(
        str(path),
        basePosition=list(base_position),
        baseOrientation=[0, 0, 0, 1],
        useFixedBase=True,
        physicsClientId=client_id,
    )
    p.resetBasePositionAndOrientation(
        body, list(base_position), [0, 0, 0, 1], physicsClientId=client_id
    )
    joints = joint_indices_by_name(body, client_id)
    links = link_indices_by_name(body, client_id)
    for name in FINGERTIP_LINK_NAMES:
        p.changeDynamics(body, links[name], physicsClientId=client_id, **FINGERTIP_DYNAMICS)
    p.enableJointForceTorqueSensor(body, joints[FT_JOINT_NAME], True, physicsClientId=client_id)
    arm = tuple(joints[name] for name in ARM_JOINT_NAMES)
    limits = [p.getJointInfo(body, i, physicsClientId=client_id)[8:10] for i in arm]
    return SawyerHandles(
        body_id=body,
        arm_joints=arm,
        finger_joints=(joints[FINGER_JOINT_NAMES[0]], joints[FINGER_JOINT_NAMES[1]]),
        fingertip_links=(links[FINGERTIP_LINK_NAMES[0]], links[FINGERTIP_LINK_NAMES[1]]),
        eef_link=links[EEF_LINK_NAME],
        ft_joint=joints[FT_JOINT_NAME],
        arm_lower=np.array([lo for lo, _ in limits]),
        arm_upper=np.array([hi for _, hi in limits]),
        root_position=np.array(root_position(base_position)),
    )


def finger_targets(gripper: float) -> tuple[float, float]:
    """RMB's finger joint targets ``(-g, +g)`` for a gripper value ``g`` (larger = wider)."""
    return (-float(gripper), float(gripper))


def reset_joints(
    client_id: int,
    handles: SawyerHandles,
    arm_qpos: Sequence[float] = HOME_ARM_QPOS,
    gripper: float = HOME_GRIPPER,
) -> None:
    """Teleport the arm and fingers to a joint configuration (zero velocity), e.g. RMB's home.

    Args:
        client_id: The pybullet physics client.
        handles: What :func:`load_sawyer_wsg50` returned.
        arm_qpos: The 7 arm joint angles.
        gripper: RMB's gripper value ``g``.
    """
    values = (*arm_qpos, *finger_targets(gripper))
    for index, value in zip(handles.controlled_joints, values, strict=True):
        p.resetJointState(handles.body_id, index, float(value), 0.0, physicsClientId=client_id)


def apply_position_targets(
    client_id: int, handles: SawyerHandles, arm_qpos: Sequence[float], gripper: float
) -> None:
    """Command RMB's position control for one substep: ``[q7, -g, +g]``, forces 200 / 20.

    Same call as RMB's ``px.Robot.set_joint_position(..., use_joint_effort_limits=False)``:
    ``POSITION_CONTROL`` with zero target velocities and pybullet's default gains.

    Args:
        client_id: The pybullet physics client.
        handles: What :func:`load_sawyer_wsg50` returned.
        arm_qpos: The 7 arm joint targets.
        gripper: RMB's gripper value ``g``.
    """
    targets = [*map(float, arm_qpos), *finger_targets(gripper)]
    if len(targets) != len(handles.controlled_joints):
        raise ValueError(f"expected 7 arm targets, got {len(targets) - 2}")
    forces = [ARM_MAX_FORCE] * len(handles.arm_joints) + [FINGER_MAX_FORCE] * 2
    p.setJointMotorControlArray(
        handles.body_id,
        list(handles.controlled_joints),
        p.POSITION_CONTROL,
        targetPositions=targets,
        targetVelocities=[0.0] * len(targets),
        forces=forces,
        physicsClientId=client_id,
    )
