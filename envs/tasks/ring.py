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

The ring is an elastic rod closed into a loop (``num_segments`` edges, inextensible), curved
so that the circle is its rest shape; its seam is at the top vertex, the one resting on the
hook, far from where the ring is gripped. How MuJoCo builds it, and why as an open rod tied
into a loop: :mod:`rmb_lerobot.envs.mujoco.tasks.ring`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

import numpy as np

from rmb_lerobot.envs.tasks.base import StartPoses, Task, placement_in
from rmb_lerobot.envs.workspace import RMB_TABLE, Workspace

if TYPE_CHECKING:
    from rmb_lerobot.envs.scene import SceneState

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

    def ring_nominal_points(self) -> np.ndarray:
        """The ring's vertices resting on the hook (the compiled pose), top vertex first."""
        angles = ring_vertex_angles(self.num_segments)
        centre = self.hook_pos + np.array([0.0, 0.0, hanging_centre_height(self.num_segments)])
        circle = RING_RADIUS * np.stack([np.zeros_like(angles), np.cos(angles), np.sin(angles)])
        return centre + circle.T

    def ring_points(self, scene: SceneState) -> np.ndarray:
        """World positions of the ring's ``num_segments`` distinct vertices (n, 3)."""
        return scene.points(RING)[: self.num_segments]

    def is_success(self, scene: SceneState) -> bool:
        pole_base = scene.body_pose(POLE)[0]
        return ring_on_pole(self.ring_points(scene), pole_base, self.success_height)
