"""RMB's MujocoUR5eCable: route a flexible cable between two poles into an S shape.

Geometry follows RMB's ``env_ur5e_cable.xml``: a 0.48 m cable of 1 cm radius lies on the table
along -y from a fixed connector at (-0.175, 0.2) to a free 4 x 3 x 3 cm end box (the part the
robot grasps); two poles (1 cm radius, 6 cm tall, 5 cm apart along x) stand at y = 0.1, the
first at x = -0.1. As in RMB only the poles move: in x from -0.03 to +0.12 m across the six
worlds (the random shift moves them in x and y). RMB's other robots' scenes move this layout
on their tables (:data:`PLACEMENTS`, keyed by workspace name): the Panda's and the dual UR5e's
keep the UR5e's numbers, the xArm7's shifts it 9.5 cm along +x (connector at (-0.08, 0.2)).
RMB's ALOHA scene (``env_aloha_cable.xml``) differs more: the connector at (-0.175, 0.25) is a
loose box (the whole cable is free on the table), the poles stand 24 cm apart at y = 0.15, and
its six worlds move them towards each other (pole 1 +1.5 cm per world, pole 2 its mirror image:
gaps 24, 21, 18, 15, 12, 9 cm; the random shift moves both poles alike).

The cable is an elastic rod of ``num_vertices`` points with inextensible edges: its first point
is pinned to the connector and its last edge is clamped inside the end box (RMB welds the box
to the last link). How MuJoCo builds it: :mod:`rmb_lerobot.envs.mujoco.tasks.cable`.

Success is RMB's ``_get_reward``: every cable point is below the pole centre height + 0.01 m,
the end box is beyond the second pole (x >= pole2 x) and at least 0.05 m on the robot's right
of the pole line (y <= pole1 y - 0.05), and some cable segment crosses the segment between the
pole centres going +y (from the connector side towards the end). RMB's ALOHA Cable has no
reward; the env uses this same rule on the ALOHA layout (the end box: the free end, cable_end).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

import numpy as np

from rmb_lerobot.envs.tasks.base import StartPoses, Task, placement_in
from rmb_lerobot.envs.workspace import RMB_TABLE, Workspace

if TYPE_CHECKING:
    from rmb_lerobot.envs.scene import SceneState

CABLE = "cable"  # the flex; vertex bodies are cable_<i>, twist joints cable_twist_<i>
CABLE_ANCHOR = "cable_anchor"
CABLE_END = "cable_end"  # the free end box (body and joint)
POLES = "poles"
POLE1, POLE2 = "pole1", "pole2"
CABLE_LENGTH = 0.48
CABLE_RADIUS = 0.01
CABLE_MASS = 0.15  # kg: each vertex weighs CABLE_MASS / num_vertices (as flexcomp does)
END_BOX_HALF_SIZE = (0.02, 0.015, 0.015)  # along the cable, across, up
END_BOX_MASS = 0.036  # kg (RMB: MuJoCo's default density)
POLE_RADIUS = 0.01
POLE_HALF_HEIGHT = 0.03
POLE_SPACING = 0.05  # pole2 is this far along +x from pole1


@dataclass(frozen=True)
class CablePlacement:
    """Where a scene puts the cable's connector and the first pole (world x, y on its table);
    the cable runs 0.48 m along -y from the connector, pole 2 stands ``pole_spacing`` along +x
    of pole 1.

    RMB's ALOHA scene differs in three ways, each a field here (the defaults are the UR5e's):
    its worlds move pole 1 along +x and pole 2 by the mirror image (``mirror_poles``: the gap
    narrows), its own ``world_offsets`` (x shifts of pole 1), and its cable lies loose on the
    table (``free_connector``: the connector box has a free joint instead of being fixed).
    """

    connector_xy: tuple[float, float]
    poles_xy: tuple[float, float]
    pole_spacing: float = POLE_SPACING
    mirror_poles: bool = False
    world_offsets: tuple[float, ...] | None = None
    free_connector: bool = False


_UR5E_PLACEMENT = CablePlacement(
    # env_ur5e_cable.xml lines 41 (cable) and 50 (poles); env_panda_cable.xml lines 40 and 49
    # and env_ur5e_dual_cable.xml lines 46 and 55 use the same numbers.
    connector_xy=(-0.175, 0.2),
    poles_xy=(-0.1, 0.1),
)
PLACEMENTS: dict[str, CablePlacement] = {
    "table": _UR5E_PLACEMENT,  # the UR5e's and the Panda's scene
    "dual_table": _UR5E_PLACEMENT,
    # env_xarm7_cable.xml lines 40 (cable at -0.08 0.2 0.755, end at -0.08 -0.28 on line 44)
    # and 49 (poles at 0.02 0.1 0.74), on the xArm table (top z 0.74).
    "xarm_table": CablePlacement(connector_xy=(-0.08, 0.2), poles_xy=(0.02, 0.1)),
    # env_aloha_cable.xml: the cable body (connector box cable_B0, with a free joint) at
    # (-0.175, 0.25), its end at (-0.175, -0.23); the poles body at (0.04, 0, 0) with pole1 at
    # (-0.12, 0.15) and pole2 at (+0.12, 0.15) in it, i.e. 24 cm apart around x = 0.04.
    # MujocoAlohaCableEnv.modify_world shifts pole1 by +0.015 m per world and puts pole2 at
    # its mirror image in the body (x -> -x): the gap shrinks from 24 to 9 cm over six worlds.
    "aloha_table": CablePlacement(
        connector_xy=(-0.175, 0.25),
        poles_xy=(-0.08, 0.15),
        pole_spacing=0.24,
        mirror_poles=True,
        world_offsets=(0.0, 0.015, 0.03, 0.045, 0.06, 0.075),
        free_connector=True,
    ),
}
"""RMB's cable layout per workspace (:attr:`Workspace.name`)."""


def crosses_between_poles(points: np.ndarray, pole1: np.ndarray, pole2: np.ndarray) -> bool:
    """Whether a segment of the cable polyline crosses the pole1-pole2 segment (in xy) with the
    cable heading to the left of the pole1 -> pole2 direction (RMB's orientation test)."""
    xy = np.asarray(points)[:, :2]
    p1, p2 = np.asarray(pole1)[:2], np.asarray(pole2)[:2]
    pole_dir = p2 - p1

    def ccw(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> bool:
        return bool((c[1] - a[1]) * (b[0] - a[0]) > (b[1] - a[1]) * (c[0] - a[0]))

    for a, b in itertools.pairwise(xy):
        if ccw(a, p1, p2) != ccw(b, p1, p2) and ccw(a, b, p1) != ccw(a, b, p2):
            cable_dir = b - a
            if pole_dir[0] * cable_dir[1] - pole_dir[1] * cable_dir[0] > 0:
                return True
    return False


def s_shape_routed(
    points: np.ndarray, end: np.ndarray, pole1: np.ndarray, pole2: np.ndarray
) -> bool:
    """RMB's Cable success test on cable points (connector first), the end box position and the
    two pole centres (all world frame)."""
    points = np.asarray(points)
    if points[:, 2].max() > pole1[2] + 0.01:
        return False
    if end[0] < pole2[0] or end[1] > pole1[1] - 0.05:
        return False
    return crosses_between_poles(points, pole1, pole2)


class CableTask(Task):
    """The cable is ``num_vertices`` points (RMB: 25 links of 2 cm). 17 (3 cm edges) steps
    ~1.6x faster than 25 (measured: ~3,700 vs ~2,300 mj_step/s with the robot) and still bends
    smoothly around a pole."""

    name = "cable"
    description = "Route the cable between the two poles into an S shape."
    world_offsets = np.array([[x, 0.0, 0.0] for x in (-0.03, 0.0, 0.03, 0.06, 0.09, 0.12)])
    max_episode_steps = 600
    # RMB's MujocoUR5eCableEnv start pose (gripper pointing down, above the cable).
    start_poses: ClassVar[StartPoses] = {
        "ur5e": ((np.pi, -np.pi / 2, -0.75 * np.pi, -0.25 * np.pi, np.pi / 2, np.pi / 2),)
    }
    num_vertices = 17
    young = 3e4  # Pa: bending stiffness E*I = 2.4e-4 N m^2, a limp rubber cable
    elastic_damping = 0.01  # s (Rayleigh)
    friction = 1.0

    def __init__(self, workspace: Workspace = RMB_TABLE) -> None:
        super().__init__(workspace)
        placement = placement_in(PLACEMENTS, workspace, self.name)
        table = workspace.table
        self.anchor_pos = table.on_top(*placement.connector_xy, CABLE_RADIUS)
        self.poles_nominal_pos = table.on_top(*placement.poles_xy)
        self.pole_spacing = placement.pole_spacing
        self.mirror_poles = placement.mirror_poles
        self.free_connector = placement.free_connector
        if placement.world_offsets is not None:
            self.world_offsets = np.array([[x, 0.0, 0.0] for x in placement.world_offsets])

    def pole2_local_x(self, world_idx: int) -> float:
        """Pole 2's x in the poles body (pole 1 at its origin) in world ``world_idx``:
        ``pole_spacing``, or, with mirrored poles, minus twice the world's x shift (pole 2 moves
        by the mirror image of pole 1's shift, as RMB's ALOHA worlds do). A random shift moves
        the body, so both poles alike: the gap stays the world's."""
        if self.mirror_poles:
            return self.pole_spacing - 2.0 * float(self.world_offsets[world_idx][0])
        return self.pole_spacing

    def cable_points(self, scene: SceneState) -> np.ndarray:
        """World positions of the cable's vertices, connector first (n, 3)."""
        return scene.points(CABLE)

    def is_success(self, scene: SceneState) -> bool:
        return s_shape_routed(
            self.cable_points(scene),
            scene.body_pose(CABLE_END)[0],
            scene.geom_pose(POLE1)[0],
            scene.geom_pose(POLE2)[0],
        )
