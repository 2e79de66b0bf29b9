"""RMB's MujocoUR5eRing: take a deformable ring off a hook and put it onto a pole.

Geometry follows RMB's ``env_ur5e_ring.xml``: a ring of 11 segments of 4 cm (0.44 m around,
7.1 cm radius) with a 1 cm tube radius, weighing 0.13 kg (RMB's 11 capsules at MuJoCo's default
density), hangs in the vertical y-z plane on a hook of two horizontal pegs along x (1 cm radius,
4 cm long) at (0.1, -0.13) and (0.1, -0.17), 0.23 m above the table; the pole (1 cm radius,
6 cm tall) stands on the table at (0, 0). As in RMB only the pole moves, by RMB's six offsets
(x in -0.04..0.04 m, y in -0.04..0.24 m); the random shift moves it in x and y.

RMB's xArm7 scene (``env_xarm7_ring.xml``) has the same objects in the same relative layout,
moved on its own table (:data:`PLACEMENTS`, keyed by :attr:`Workspace.name`): hook at
(0.3, -0.15), 0.25 m above the table, pole at (0.2, 0) moved along +y by 0..0.20 m, and its pole
body origin on the table top, so there RMB's success height (origin + 0.08 m) is 2 cm above the
pole's top.

Success is RMB's ``MujocoUR5eRingEnv._get_reward`` (read in the mmurooka/RoboManipBaselines
fork of isri-aist/RoboManipBaselines): the highest ``ring_B*`` body (points on the tube's centre
line) must not be above ``pole body origin z + 0.08 m``, and the pole origin's xy must lie inside
the polygon of those points (matplotlib ``Path.contains_point``). In RMB's ``env_ur5e_ring.xml`` the
pole body sits at z = 0.795, 2 cm *below* the table top (0.815), and its cylinder (half height
0.03 m at +0.05 m) spans origin + 0.02 .. origin + 0.08 m: RMB's threshold is exactly the pole's
top, 6 cm above the table. Here the pole body's origin is at the pole's base on the table, so
the same threshold is origin + ``SUCCESS_HEIGHT`` = origin + ``POLE_HEIGHT``, tested on the
flex vertices (also on the tube's centre line). Note: the issue's wording "below pole top +
0.08 m" would, read literally, accept a ring 8 cm above the pole's top; this task follows RMB's
code instead, where the 0.08 m is measured from the pole body's origin, i.e. up to the top.

The ring is MuJoCo's discrete elastic rod (a 1D flex with bending/twist elasticity and
inextensible edges), curved in its compiled pose so that the circle is its rest shape. MuJoCo 4
supports closed 1D flex loops (``flexcomp type="circle"``), but closed loops carry no per-edge
twist joints, and only those let contact friction act on the tube's rotation about its own axis:
a closed loop pinched by the gripper turns freely about the pinched segment like a bead on a
wire, so it can never be held in a chosen plane. This task therefore builds the ring as an open
rod of ``num_segments`` edges with twist joints (named as MuJoCo's rod model binds them) whose
last vertex is tied to the first by a ``connect`` equality: a loop that grips like a plastic
ring. The seam is a ball joint (no bending stiffness across it); it is placed at the top vertex,
the one resting on the hook, far from where the ring is gripped.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

import mujoco
import numpy as np

from rmb_lerobot.envs.tasks.base import StartPoses, Task, placement_in
from rmb_lerobot.envs.workspace import RMB_TABLE, Workspace

if TYPE_CHECKING:
    from rmb_lerobot.envs.backend import SceneState
    from rmb_lerobot.envs.mujoco.backend import MujocoBackend

RING = "ring"  # the flex; vertex bodies ring_<i>, twist joints ring_twist_<e> and ring_twist
SEAM = "ring_seam"  # the equality closing the loop
HOOK = "hook"
PEG1, PEG2 = "hook_peg1", "hook_peg2"
POLE = "pole"
NUM_SEGMENTS = 11
SEGMENT_LENGTH = 0.04
RING_RADIUS = SEGMENT_LENGTH / (2 * np.sin(np.pi / NUM_SEGMENTS))  # centre to vertex, 7.1 cm
TUBE_RADIUS = 0.01
RING_MASS = 0.13
PEG_RADIUS = 0.01
PEG_HALF_LENGTH = 0.02
# RMB's peg y and the hook centre between them (the same in env_ur5e_ring.xml lines 56-59 and
# env_xarm7_ring.xml lines 54-57): the pegs stand +-2 cm along y from the hook centre.
PEG_Y = (-0.13, -0.17)
HOOK_XY = (0.1, -0.15)  # between the pegs, on their axes (the UR5e scene's)
HOOK_HEIGHT = 0.23  # above the table top (the UR5e scene's)
POLE_RADIUS = 0.01
POLE_HEIGHT = 0.06
# RMB's success height: 0.08 m above its pole body origin, which lies 0.02 m below the pole's
# base (the table top); measured from this task's pole origin (the base) that is the pole's top.
RMB_SUCCESS_HEIGHT = 0.08
RMB_POLE_ORIGIN_DEPTH = 0.02
SUCCESS_HEIGHT = RMB_SUCCESS_HEIGHT - RMB_POLE_ORIGIN_DEPTH  # = POLE_HEIGHT


def ring_vertex_angles(num_segments: int = NUM_SEGMENTS) -> np.ndarray:
    """Angles of the ring's vertices in its own plane, starting at the top (pi / 2) and going
    round once; with an odd count a segment lies flat at the bottom."""
    return np.pi / 2 + 2 * np.pi * np.arange(num_segments) / num_segments


@dataclass(frozen=True)
class RingPlacement:
    """Where a scene puts the hook and the pole (world x, y on its table), the hook's height
    above the table top, how far RMB's pole body origin lies below the pole's base (its success
    height is origin + 0.08 m), and the pole's six world offsets."""

    hook_xy: tuple[float, float]
    hook_height: float
    pole_xy: tuple[float, float]
    pole_origin_depth: float
    world_offsets: np.ndarray

    @property
    def success_height(self) -> float:
        """RMB's success threshold above the pole's base (m)."""
        return RMB_SUCCESS_HEIGHT - self.pole_origin_depth


PLACEMENTS: dict[str, RingPlacement] = {
    # env_ur5e_ring.xml lines 45-64: ring, hook and pole bodies at (0, 0, 0.795), 2 cm below
    # the table top (0.815); pegs at (0.1, -0.13/-0.17, 0.25) from there, i.e. 0.23 m above the
    # table; the pole cylinder 2..8 cm above its origin.
    "table": RingPlacement(
        hook_xy=HOOK_XY,
        hook_height=HOOK_HEIGHT,
        pole_xy=(0.0, 0.0),
        pole_origin_depth=RMB_POLE_ORIGIN_DEPTH,
        # The six pole offsets of RMB's MujocoUR5eRingEnv (mmurooka fork, see the docstring).
        world_offsets=np.array(
            [
                [0.0, -0.04, 0.0],
                [0.04, 0.08, 0.0],
                [-0.04, 0.08, 0.0],
                [0.04, 0.12, 0.0],
                [-0.04, 0.12, 0.0],
                [0.0, 0.24, 0.0],
            ]
        ),
    ),
    # env_xarm7_ring.xml lines 43-62: ring, hook and pole bodies at (0.2, 0, 0.74), on the
    # table top (0.74); pegs at (0.1, -0.13/-0.17, 0.25) from there; the pole cylinder 0..6 cm
    # above its origin (line 61), so the origin is the pole's base.
    "xarm_table": RingPlacement(
        hook_xy=(0.3, -0.15),
        hook_height=0.25,
        pole_xy=(0.2, 0.0),
        pole_origin_depth=0.0,
        # MujocoXarm7RingEnv.py lines 26-35: the pole moves along +y, 0..0.20 m.
        world_offsets=np.array([[0.0, 0.04 * i, 0.0] for i in range(6)]),
    ),
}
"""RMB's ring layout per workspace (:attr:`Workspace.name`)."""


def ring_on_pole(
    points: np.ndarray, pole_base: np.ndarray, success_height: float = SUCCESS_HEIGHT
) -> bool:
    """RMB's Ring success test on the ring's vertices (n, 3) and the pole's base centre: no
    vertex higher than ``success_height`` above the base (RMB's origin + 0.08 m: the pole's top
    in the UR5e scene) and the pole's axis inside the ring polygon."""
    points = np.asarray(points)
    if points[:, 2].max() > pole_base[2] + success_height:
        return False
    return inside_polygon(points[:, :2], np.asarray(pole_base)[:2])


def inside_polygon(polygon: np.ndarray, point: np.ndarray) -> bool:
    """Even-odd ray test: whether ``point`` (2,) lies inside the closed polygon (n, 2) (RMB
    uses matplotlib's ``Path.contains_point``, the same test)."""
    x, y = point
    xs, ys = polygon[:, 0], polygon[:, 1]
    xn, yn = np.roll(xs, -1), np.roll(ys, -1)
    straddles = (ys > y) != (yn > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        x_cross = xs + (y - ys) * (xn - xs) / (yn - ys)
    return bool(np.count_nonzero(straddles & (x < x_cross)) % 2)


def hanging_centre_height(num_segments: int = NUM_SEGMENTS) -> float:
    """Height of the ring centre above the peg axes when the ring rests on both pegs.

    The two segments next to the top vertex rest on the pegs: their centre lines are
    ``TUBE_RADIUS + PEG_RADIUS`` from the peg axes (at +-2 cm from the ring's centre plane).
    """
    angles = ring_vertex_angles(num_segments)[:2]
    top, nxt = RING_RADIUS * np.stack([np.cos(angles), np.sin(angles)], axis=1)
    direction = (nxt - top) / np.linalg.norm(nxt - top)
    normal = np.array([-direction[1], direction[0]])
    normal *= np.sign(normal[1])  # the segment's upper side
    peg = np.array([np.sign(nxt[0]) * abs(PEG_Y[0] - HOOK_XY[1]), 0.0])  # under that segment
    # With the centre c above the peg: (top + (0, c) - peg) . normal = clearance.
    clearance = TUBE_RADIUS + PEG_RADIUS
    return float((clearance - (top - peg) @ normal) / normal[1])


class RingTask(Task):
    """The ring is an elastic rod (Young's modulus ``young``, a stiff plastic): it keeps its
    shape when held at one point, bends under a squeeze."""

    name = "ring"
    description = "Pick up the ring hanging on the hook and place it onto the pole."
    # The default workspace's worlds; an instance has its own workspace's (``__init__``).
    world_offsets = PLACEMENTS[RMB_TABLE.name].world_offsets
    max_episode_steps = 500
    start_poses: ClassVar[StartPoses] = {
        # RMB's MujocoUR5eRingEnv start pose: the hand points along +x at the hook's height.
        "ur5e": ((np.pi, -np.pi / 2, -0.75 * np.pi, -0.75 * np.pi, -0.5 * np.pi, 0.0),),
        # MujocoXarm7RingEnv.py line 21.
        "xarm7": ((0.0, 0.0, 0.0, 0.0, np.pi, np.pi / 2, np.pi),),
    }
    num_segments = NUM_SEGMENTS
    young = 1e7  # Pa: bending stiffness E*I = 0.08 N m^2
    elastic_damping = 0.005  # s (Rayleigh)
    friction = 1.0

    def __init__(self, workspace: Workspace = RMB_TABLE) -> None:
        super().__init__(workspace)
        self.placement = placement_in(PLACEMENTS, workspace, self.name)
        self.world_offsets = self.placement.world_offsets
        self.success_height = self.placement.success_height
        self.hook_pos = workspace.table.on_top(*self.placement.hook_xy, self.placement.hook_height)
        self.pole_nominal_pos = workspace.table.on_top(*self.placement.pole_xy)

    def build(self, spec: mujoco.MjSpec, sim: MujocoBackend) -> None:
        spec.option.integrator = mujoco.mjtIntegrator.mjINT_DISCRETE
        hook = spec.worldbody.add_body(name=HOOK, pos=list(self.hook_pos))
        for name, y in ((PEG1, PEG_Y[0]), (PEG2, PEG_Y[1])):
            hook.add_geom(
                name=name,
                type=mujoco.mjtGeom.mjGEOM_CYLINDER,
                size=[PEG_RADIUS, PEG_HALF_LENGTH, 0],
                pos=[0, y - HOOK_XY[1], 0],  # RMB's offsets from its hook centre
                quat=[np.cos(np.pi / 4), 0, np.sin(np.pi / 4), 0],  # axis along x
                rgba=[0.8, 0.1, 0.5, 1.0],
            )
        pole = spec.worldbody.add_body(name=POLE, pos=list(self.pole_nominal_pos))
        pole.add_geom(
            type=mujoco.mjtGeom.mjGEOM_CYLINDER,
            size=[POLE_RADIUS, POLE_HEIGHT / 2, 0],
            pos=[0, 0, POLE_HEIGHT / 2],
            rgba=[0.1, 0.5, 0.8, 1.0],
        )
        self._build_ring(spec)

    def ring_nominal_points(self) -> np.ndarray:
        """The ring's vertices resting on the hook (the compiled pose), top vertex first."""
        angles = ring_vertex_angles(self.num_segments)
        centre = self.hook_pos + np.array([0.0, 0.0, hanging_centre_height(self.num_segments)])
        circle = RING_RADIUS * np.stack([np.zeros_like(angles), np.cos(angles), np.sin(angles)])
        return centre + circle.T

    def _build_ring(self, spec: mujoco.MjSpec) -> None:
        """Vertices 0..n-1 on bodies with three slide joints, vertex n on a further body at
        vertex 0's place (the open rod's end), tied to it by the seam; one twist hinge per edge."""
        n = self.num_segments
        points = self.ring_nominal_points()
        vertex_mass = RING_MASS / (n + 1)
        inertia = [vertex_mass * 1e-4] * 3  # point masses; MuJoCo needs a rotational inertia
        bodies = []
        for i in range(n + 1):
            body = spec.worldbody.add_body(
                name=f"{RING}_{i}", pos=list(points[i % n]), mass=vertex_mass, inertia=inertia
            )
            for axis in np.eye(3):
                body.add_joint(type=mujoco.mjtJoint.mjJNT_SLIDE, axis=list(axis))
            bodies.append(body.name)

        edge_inertia = 0.5 * (RING_MASS / n) * TUBE_RADIUS**2
        for e in range(n):  # MuJoCo's rod names: ring_twist_0 .. ring_twist_{n-2}, ring_twist
            name = f"{RING}_twist_{e}" if e < n - 1 else f"{RING}_twist"
            twist = spec.worldbody.add_body(name=name, mass=1e-9, inertia=[edge_inertia] * 3)
            twist.add_joint(name=name, type=mujoco.mjtJoint.mjJNT_HINGE, axis=[1, 0, 0])

        flex = spec.add_flex()
        flex.name = RING
        flex.dim = 1
        flex.radius = TUBE_RADIUS
        flex.vertbody = bodies
        flex.vert = [0.0] * (3 * (n + 1))
        flex.elem = [v for e in range(n) for v in (e, e + 1)]
        flex.young = self.young
        flex.damping = self.elastic_damping
        flex.selfcollide = mujoco.mjtFlexSelf.mjFLEXSELF_NONE  # a stiff ring cannot fold
        flex.friction = [self.friction, 0.005, 0.0001]
        flex.rgba = [0.8, 0.8, 0.2, 1.0]
        # Inextensible edges, stiff enough for light vertices (see the Cable task).
        solref = [2 * spec.option.timestep, 1.0]
        solimp = [0.95, 0.99, 0.001, 0.5, 2.0]
        spec.add_equality(type=mujoco.mjtEq.mjEQ_FLEX, name1=RING, solref=solref, solimp=solimp)
        spec.add_equality(
            name=SEAM,
            type=mujoco.mjtEq.mjEQ_CONNECT,
            objtype=mujoco.mjtObj.mjOBJ_BODY,
            name1=f"{RING}_{n}",
            name2=f"{RING}_0",
            data=[0.0] * 12,
            solref=solref,
            solimp=solimp,
        )

    def apply_world(self, sim: MujocoBackend, offset: np.ndarray) -> None:
        sim.model.body(POLE).pos = self.pole_nominal_pos + offset

    def reset_objects(self, sim: MujocoBackend) -> None:
        """Nothing to do: the ring starts at rest on the hook in its build pose (``qpos0``),
        where ``mj_resetData`` already put it along with the rod's reference frames."""

    def ring_points(self, scene: SceneState) -> np.ndarray:
        """World positions of the ring's ``num_segments`` distinct vertices (n, 3)."""
        return scene.points(RING)[: self.num_segments]

    def is_success(self, scene: SceneState) -> bool:
        pole_base = scene.body_pose(POLE)[0]
        return ring_on_pole(self.ring_points(scene), pole_base, self.success_height)
