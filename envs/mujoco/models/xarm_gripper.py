"""RMB's xArm gripper, drawn with primitives: the same joints, linkage, pads and command.

No installable package ships the xArm gripper with a clear licence (see docs/robot-models.md),
so this module rebuilds the mechanism of RMB's ``robots/xarm7/xarm7_body.xml`` (lines 43-101)
and ``xarm7_config.xml`` (lines 48-100) at RMB commit 8535948 in code:

- six hinge joints (``left/right_driver_joint``, ``*_inner_knuckle_joint``, ``*_finger_joint``),
  RMB's ranges, armatures, dampings, springs and limit softness (its classes ``driver``,
  ``spring_link``, ``follower``), and its inertials (UFACTORY's numbers);
- RMB's modified linkage: each finger hangs from its *inner* knuckle and five joint equalities
  (``polycoef 0 1``) make all six joints follow ``left_driver_joint``;
- RMB's grasp fix: the finger shapes do not collide; two box pads per finger do
  (friction 0.7 / 0.6, ``solref 0.004 1``, priority 1);
- the actuator: ``general`` on the tendon ``split`` (half of each driver), ctrl 0..255,
  gain 0.3137255 = 0.8 * 100 / 255, bias (0, -100, -10), |force| <= 100: command 255 holds the
  drivers at 0.8 rad. RMB measures ``mean(6 joints) / 0.8 * 255``.

Only the looks differ: boxes sized from RMB's meshes' extents (measured), not the meshes.
Body frame: RMB's ``xarm_gripper_base_link`` (z along the fingers, fingers open along +-y).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from rmb_lerobot.envs.mujoco.models.common import euler_quat
from rmb_lerobot.envs.robots import Gripper

ROOT_BODY = "xarm_gripper_base_link"
ACTUATOR = "gripper"
TENDON = "split"

_WHITE, _BLACK, _GRAY = (1.0, 1.0, 1.0, 1.0), (0.149, 0.149, 0.149, 1.0), (0.55, 0.55, 0.55, 1.0)
# xarm7_config.xml lines 48-56 (classes spring_link, driver, follower); solimp's two trailing
# numbers are MuJoCo's defaults, which RMB's three-number solimp leaves in place.
_SOLIMP = [0.95, 0.99, 0.001, 0.5, 2.0]
_SOLREF = [0.005, 1.0]
# xarm7_body.xml lines 49-98: (pos in parent, inertial pos, inertial quat, mass, diaginertia)
# of the left side; the right side mirrors y.
_OUTER = ((0, 0.035, 0.059098), (0, 0.021559, 0.015181), (0.47789, 0.87842, 0, 0), 0.033618,
          (1.9111e-05, 1.79089e-05, 1.90167e-06))  # fmt: skip
_INNER = ((0, 0.02, 0.074098), (1.86601e-06, 0.0220468, 0.0261335),
          (0.664139, -0.242732, 0.242713, 0.664146), 0.0230126,
          (8.34216e-06, 6.0949e-06, 2.75601e-06))  # fmt: skip
_FINGER = ((0, 0.035465, 0.042039), (0, -0.016413, 0.029258),
           (0.697634, 0.115353, -0.115353, 0.697634), 0.048304,
           (1.88037e-05, 1.7493e-05, 3.56792e-06))  # fmt: skip
# xarm7_config.xml lines 79-88 (joint1, joint2): every joint follows the left driver.
_EQUALITIES = (
    ("left_driver_joint", "right_driver_joint"),
    ("left_driver_joint", "left_inner_knuckle_joint"),
    ("left_driver_joint", "left_finger_joint"),
    ("right_driver_joint", "right_inner_knuckle_joint"),
    ("right_driver_joint", "right_finger_joint"),
)
_RIGHT_INERTIALS = {  # RMB's right-side numbers differ from the mirrored left in the last digits
    "inner": ((1.866e-06, -0.022047, 0.026133), (0.66415, 0.242702, -0.242721, 0.664144),
              0.023013, (8.34209e-06, 6.0949e-06, 2.75601e-06)),
    "finger": ((0, 0.016413, 0.029258), (0.697634, -0.115356, 0.115356, 0.697634), 0.048304,
               (1.88038e-05, 1.7493e-05, 3.56779e-06)),
    "outer": ((0, -0.021559, 0.015181), (0.87842, 0.47789, 0, 0), 0.033618,
              (1.9111e-05, 1.79089e-05, 1.90167e-06)),
}  # fmt: skip


def _bar(body: mujoco.MjsBody, p0, p1, half_x: float, half_t: float, rgba) -> None:
    """Render-only box from ``p0`` to ``p1`` (both in the y-z plane), ``half_x`` wide."""
    p0, p1 = np.asarray(p0, dtype=np.float64), np.asarray(p1, dtype=np.float64)
    d = p1 - p0
    length = float(np.linalg.norm(d))
    body.add_geom(
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[half_x, half_t, length / 2],
        pos=((p0 + p1) / 2).tolist(),
        quat=euler_quat((math.atan2(-d[1], d[2]), 0.0, 0.0)),
        rgba=list(rgba),
        contype=0,
        conaffinity=0,
        group=2,
    )


def _inertial(body: mujoco.MjsBody, ipos, iquat, mass, inertia) -> None:
    body.ipos, body.iquat, body.mass, body.inertia = list(ipos), list(iquat), mass, list(inertia)
    body.explicitinertial = True


def _side(spec: mujoco.MjSpec, base: mujoco.MjsBody, side: str, s: float) -> None:
    """One side of the linkage; ``s`` = +1 (left) or -1 (right) mirrors y and the axes."""

    def mirror(v):
        return [v[0], s * v[1], v[2]]

    right = _RIGHT_INERTIALS if s < 0 else None
    outer = base.add_body(name=f"{side}_outer_knuckle", pos=mirror(_OUTER[0]))
    _inertial(outer, *(right["outer"] if right else _OUTER[1:]))
    outer.add_joint(
        name=f"{side}_driver_joint",
        axis=[s, 0, 0],
        range=[0, 0.85],
        armature=0.005,
        damping=[0.1, 0, 0],
        solref_limit=_SOLREF,
        solimp_limit=_SOLIMP,
    )
    # RMB left_outer_knuckle.stl: a lever from y -0.026 to the finger pivot (measured extents).
    _bar(outer, mirror((0, -0.02, -0.004)), mirror(_FINGER[0]), 0.006, 0.006, _BLACK)

    inner = base.add_body(name=f"{side}_inner_knuckle", pos=mirror(_INNER[0]))
    _inertial(inner, *(right["inner"] if right else _INNER[1:]))
    inner.add_joint(
        name=f"{side}_inner_knuckle_joint",
        axis=[s, 0, 0],
        range=[0, 0.85],
        armature=0.001,
        stiffness=[0.05, 0, 0],
        springref=2.62,
        damping=[0.00125, 0, 0],
    )
    # RMB left_inner_knuckle.stl: 28 mm wide bar between its pivots (measured extents).
    _bar(inner, (0, 0, 0), mirror(_FINGER[0]), 0.014, 0.005, _BLACK)

    finger = inner.add_body(name=f"{side}_finger", pos=mirror(_FINGER[0]))
    _inertial(finger, *(right["finger"] if right else _FINGER[1:]))
    finger.add_joint(
        name=f"{side}_finger_joint",
        axis=[-s, 0, 0],
        range=[0, 0.85],
        armature=0.001,
        solref_limit=_SOLREF,
        solimp_limit=_SOLIMP,
    )
    # RMB left_finger.stl, placed at (0, 0.015, -0.015) in the finger body: a 32 mm wide plate
    # y -0.011..0.003, z -0.004..0.046 and its root block y 0.006..0.021, z -0.021..-0.004.
    visual = {"contype": 0, "conaffinity": 0, "group": 2, "rgba": list(_BLACK)}
    box = mujoco.mjtGeom.mjGEOM_BOX
    finger.add_geom(type=box, size=[0.016, 0.007, 0.025], pos=mirror((0, -0.004, 0.021)), **visual)
    finger.add_geom(
        type=box, size=[0.01, 0.0075, 0.0085], pos=mirror((0, 0.0135, -0.0125)), **visual
    )
    # The pads (xarm7_body.xml lines 65-72 / 91-98): the only finger geoms that collide.
    pad = finger.add_body(pos=mirror((0.0, -0.006, 0.0275)), quat=euler_quat((s * 0.05, 0, 0)))
    for z, friction, rgba in ((0.009, 0.7, (0.55,) * 3), (-0.009, 0.6, (0.45,) * 3)):
        pad.add_geom(
            type=box,
            size=[0.014, 0.005, 0.009],
            pos=[0.0, 0.0, z],
            friction=[friction, 0.005, 0.0001],
            solimp=_SOLIMP,
            solref=[0.004, 1.0],
            priority=1,
            condim=3,
            group=3,
            rgba=[*rgba, 1.0],
        )
    # xarm7_config.xml lines 61-66.
    for other in (outer, finger):
        spec.add_exclude(bodyname1=inner.name, bodyname2=other.name)


def add_xarm_gripper(
    spec: mujoco.MjSpec,
    parent: mujoco.MjsBody,
    gripper: Gripper,
    tcp_site: str,
    quat: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0),
) -> mujoco.MjsBody:
    """Build the gripper into ``spec`` under ``parent``.

    Built in place rather than attached from a spec of its own, so its names stay RMB's
    unprefixed ones (the record's gripper joints are six of them: RMB's
    ``MujocoXarm7EnvBase._get_obs``, lines 103-124, measures their mean / 0.8 * 255).

    Args:
        spec: The arm's spec (radians).
        parent: The body the gripper is mounted on.
        gripper: The record's gripper: its command range is the actuator's.
        tcp_site: The record's tool-centre frame, made a site between the fingertips.
        quat: The gripper's orientation on ``parent``.

    Returns:
        The gripper's root body, :data:`ROOT_BODY`.

    Raises:
        ValueError: If ``spec`` works in degrees.
    """
    if spec.compiler.degree:
        raise ValueError("add_xarm_gripper needs a spec with compiler.degree = False (radians)")
    base = parent.add_body(name=ROOT_BODY, quat=list(quat))
    # xarm7_body.xml lines 46-47.
    _inertial(
        base,
        (-0.00065489, -0.0018497, 0.048028),
        (0.997403, -0.0717512, -0.0061836, 0.000477479),
        0.54156,
        (0.000471093, 0.000332307, 0.000254799),
    )
    # RMB base_link.stl (collides in RMB): a flange z -0.009..0.005 about 75 mm across and a
    # housing x -0.028..0.025, y -0.051..0.051, z 0.005..0.103 (measured extents).
    base.add_geom(
        type=mujoco.mjtGeom.mjGEOM_CYLINDER, size=[0.0375, 0.007, 0], pos=[0, 0, -0.002],
        rgba=list(_WHITE),
    )  # fmt: skip
    base.add_geom(
        type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.0265, 0.051, 0.049], pos=[-0.0015, 0, 0.054],
        rgba=list(_WHITE),
    )  # fmt: skip
    base.add_site(name=tcp_site, pos=[0, 0, 0.172], size=[0.001, 0, 0], group=4)  # line 101
    _side(spec, base, "left", 1.0)
    _side(spec, base, "right", -1.0)

    tendon = spec.add_tendon(name=TENDON)  # xarm7_config.xml lines 68-73
    tendon.wrap_joint("right_driver_joint", 0.5)
    tendon.wrap_joint("left_driver_joint", 0.5)
    for leader, follower in _EQUALITIES:
        eq = spec.add_equality(
            type=mujoco.mjtEq.mjEQ_JOINT, name1=leader, name2=follower, solref=_SOLREF,
            solimp=_SOLIMP,
        )  # fmt: skip
        eq.data[0:5] = [0, 1, 0, 0, 0]  # polycoef: follower = leader
    act = spec.add_actuator(name=ACTUATOR, target=TENDON, trntype=mujoco.mjtTrn.mjTRN_TENDON)
    act.gaintype, act.biastype = mujoco.mjtGain.mjGAIN_FIXED, mujoco.mjtBias.mjBIAS_AFFINE
    act.gainprm[0] = 0.3137255  # xarm7_config.xml lines 99-100
    act.biasprm[0:3] = [0.0, -100.0, -10.0]
    act.ctrlrange, act.ctrllimited = list(gripper.command_range), mujoco.mjtLimited.mjLIMITED_TRUE
    act.forcerange, act.forcelimited = [-100.0, 100.0], mujoco.mjtLimited.mjLIMITED_TRUE
    return base
