"""RMB's MujocoUR5eCloth: lift a cloth hanging from a board and lay it up onto the board.

Geometry follows RMB's ``env_ur5e_cloth.xml``: a 12 x 36 x 1.6 cm board floats 0.385 m above
the table at (0.15, -0.065, 1.2), turned by -45 degrees about the vertical (its long side
runs along the world (1, 1) diagonal, facing the robot). A 32 x 24 cm cloth, a 9 x 7 grid of
points 4 cm apart (RMB's ``composite`` grid), hangs vertically from its top row, which is fixed
just outside and 3 cm below the board's robot-side edge (RMB welds that row to the board); the
cloth's bottom edge is 11.5 cm above the table. As in RMB the cloth and the board move
together: in y from -0.12 to +0.08 m across the six worlds, and the random shift moves both in
x, y and z (RMB shifts them in all three axes).

The cloth is MuJoCo's 2D flex (triangulated grid, three slide joints per free vertex),
generated with :meth:`mujoco.MjsBody.make_flex` (the ``flexcomp`` macro of MjSpec) as a child
of the board. ``make_flex`` has no pins, so the top row is pinned by removing the joints of its
vertex bodies: they are then welded to the board, which is exactly what pinning does. The
cloth is inextensible (flex edge equality constraints) and has no bending stiffness, like
RMB's composite cloth; this keeps the scene on the fast ``implicitfast`` integrator (a shell
with continuum elasticity needs the ``discrete`` integrator and stepped ~4x slower here).
The cloth weighs RMB's 2.1 kg (its 63 spheres of water density) and does not collide with
itself (cheaper; the task never needs it to).

Robustness. Uniformly random joint targets swing the simulated arm at up to ~11 m/s at the
tool (10x a real UR5e) into the cloth and the board. A light cloth (0.1 kg before) then broke
the simulation in three ways, all measured over 120 such rollouts (``benchmarks/RESULTS.md``):
MuJoCo's constraint softness is set per unit mass, so against the arm's forces the edges and
contacts of light points are weak; the gripper pads' stiff rubber contact flung touched
points at 10-25 m/s (4-10 cm per 4 ms step, more than the 4 cm edge, which the linearised
edge constraints cannot follow: edges stretched 2.5-4x); and MuJoCo 4.0.0's Newton solver
diverged now and then (see :data:`SOLVER`). Hence RMB's mass, the cloth's own contact
softness for all its contacts (:data:`CONTACT_PRIORITY`) and the CG solver.

Success is RMB's ``_get_success``: every cloth point is above the board's lowest corner minus
0.092 m in z (the cloth is lifted up to the board) and beyond the board's smallest corner x
minus 0.001 m (it was not pulled off towards the robot).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, ClassVar

import mujoco
import numpy as np

from rmb_lerobot.envs.tasks.base import StartPoses, Task
from rmb_lerobot.envs.workspace import RMB_TABLE, Workspace

if TYPE_CHECKING:
    from rmb_lerobot.envs.backend import SceneState
    from rmb_lerobot.envs.mujoco.backend import MujocoBackend

CLOTH = "cloth"  # the flex; its vertex bodies are cloth_<i>, i = row * CLOTH_COLUMNS + column
BOARD = "board"  # the body and its box geom
BOARD_HALF_SIZE = (0.06, 0.18, 0.008)  # across, along the cloth's top edge, thickness
CLOTH_ROWS = 7  # top row (row 0, pinned) to bottom edge
CLOTH_COLUMNS = 9  # along the board
CLOTH_SPACING = 0.04  # m between neighbouring grid points
CLOTH_MASS = 2.1  # kg, RMB's (63 spheres of water density). MuJoCo's constraint softness is
# per unit mass: at 0.1 kg the pads closed through the cloth unless they kept their own stiff
# contact, and random arm strikes stretched edges up to 3x (2.58x at 0.5 kg, 2.03x at 2.1 kg
# over 120 rollouts; RESULTS.md). The expert lifts it too, but slips more (RESULTS.md).
CLOTH_RADIUS = 0.006  # collision half thickness (m): pinchable, and no tunnelling (RMB: 0.02)
# Every cloth contact uses the cloth's contact softness, MuJoCo's default (time constant 20 ms,
# impedance 0.9-0.95), also against the gripper pads, whose own contact (priority 1: time
# constant 4 ms, clamped to 8 ms, impedance 0.95-0.99) matches a touched point's velocity to
# the pad's within one step and flung points at 10-25 m/s under random arm motion.
CONTACT_PRIORITY = 2
# Fabric on the rubber pads (and, by priority, on everything): with RMB's 2.1 kg the pinch at
# friction 1.0 let the cloth slip out of 4 of 6 hard expert episodes (47, 83 and others),
# 1.5 held them; it still slips in 2 of 100 (RESULTS.md).
CLOTH_FRICTION = 1.5
CONTACT_SOLREF = (0.02, 1.0)
CONTACT_SOLIMP = (0.9, 0.95, 0.001, 0.5, 2.0)
# MuJoCo 4.0.0's sparse Newton solver can get a wrong Hessian factor (fixed upstream in 4.0.1,
# google-deepmind/mujoco #3767): where the cloth touches both fingers' links, a step diverged
# (cloth points at ~900 m/s, or MuJoCo reset the state on a huge acceleration) in about 1 of
# 30 random-action rollouts; the same states solve correctly with a dense Jacobian (4-8x
# slower) or CG, which never factorises the Hessian. CG costs ~1.3 ms more per env step in
# expert episodes (RESULTS.md). Back to Newton once the project is on MuJoCo >= 4.0.1.
SOLVER = mujoco.mjtSolver.mjSOL_CG
# RMB's cloth body origin relative to the board centre (from its world numbers, in the order
# RMB's file gives them: cloth origin (0.11, 0.003, 1.05) minus board (0.15, -0.065, 1.2)).
CLOTH_FROM_BOARD = np.array([0.11, 0.003, 1.05]) - np.array([0.15, -0.065, 1.2])
SUCCESS_X_MARGIN = 0.001  # RMB: cloth x must exceed the board's smallest corner x minus this
SUCCESS_Z_MARGIN = 0.092  # RMB: cloth z must exceed the board's lowest corner z minus this


def board_corners(center: np.ndarray, rotation: np.ndarray, half_size: np.ndarray) -> np.ndarray:
    """World positions (8, 3) of a box's corners from its centre, rotation matrix, half sizes."""
    signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
    return (np.asarray(rotation).reshape(3, 3) @ (signs * half_size).T).T + center


def cloth_on_board(points: np.ndarray, corners: np.ndarray) -> bool:
    """RMB's Cloth success test on the cloth grid points (n, 3) and the board corners (8, 3)."""
    points = np.asarray(points)
    x_threshold = corners[:, 0].min() - SUCCESS_X_MARGIN
    z_threshold = corners[:, 2].min() - SUCCESS_Z_MARGIN
    return bool(points[:, 0].min() > x_threshold and points[:, 2].min() > z_threshold)


class ClothTask(Task):
    """The cloth is RMB's 9 x 7 grid (63 vertices, 54 free: 162 dofs)."""

    name = "cloth"
    description = "Lift the hanging cloth and roll it up onto the board."
    world_offsets = np.array([[0.0, y, 0.0] for y in (-0.12, -0.08, -0.04, 0.0, 0.04, 0.08)])
    shift_axes = np.array([1.0, 1.0, 1.0])
    max_episode_steps = 400
    # RMB's MujocoUR5eClothEnv start pose.
    start_poses: ClassVar[StartPoses] = {
        "ur5e": ((1.2 * np.pi, -np.pi / 2, -0.85 * np.pi, -0.65 * np.pi, -0.5 * np.pi, 0.0),)
    }
    board_yaw = -np.pi / 4
    friction = 1.0

    def __init__(self, workspace: Workspace = RMB_TABLE) -> None:
        super().__init__(workspace)
        # RMB's board centre, 0.385 m above its table top at (0.15, -0.065) (world 1.2 m).
        self.board_nominal_pos = workspace.table.on_top(0.15, -0.065, 0.385)
        self.cloth_centre = self.board_nominal_pos + CLOTH_FROM_BOARD

    @property
    def board_quat(self) -> np.ndarray:
        return np.array([np.cos(self.board_yaw / 2), 0.0, 0.0, np.sin(self.board_yaw / 2)])

    def build(self, spec: mujoco.MjSpec, sim: MujocoBackend) -> None:
        board = spec.worldbody.add_body(
            name=BOARD, pos=list(self.board_nominal_pos), quat=list(self.board_quat)
        )
        board.add_geom(
            name=BOARD,
            type=mujoco.mjtGeom.mjGEOM_BOX,
            size=list(BOARD_HALF_SIZE),
            rgba=[0.8, 0.8, 0.2, 1.0],
            friction=[self.friction, 0.005, 0.0001],
        )
        self._build_cloth(spec, board)

    def _build_cloth(self, spec: mujoco.MjSpec, board: mujoco.MjsBody) -> None:
        """The flex grid in the board frame: grid x (rows) points down, grid y along the
        board's long side, so point ``row * CLOTH_COLUMNS + column`` sits in row ``row``."""
        yaw = self.board_yaw
        offset = CLOTH_FROM_BOARD
        across = np.array([np.cos(yaw), np.sin(yaw), 0.0])  # board x axis in the world
        along = np.array([-np.sin(yaw), np.cos(yaw), 0.0])  # board y axis in the world
        centre = [offset @ across, offset @ along, offset[2]]
        down = [np.cos(np.pi / 4), 0.0, np.sin(np.pi / 4), 0.0]  # grid x -> board -z
        flex = board.make_flex(
            name=CLOTH,
            type="grid",
            dim=2,
            count=[CLOTH_ROWS, CLOTH_COLUMNS, 1],
            spacing=[CLOTH_SPACING] * 3,
            mass=CLOTH_MASS,
            radius=CLOTH_RADIUS,
            equality=1,  # inextensible edges
            pos=centre,
            quat=down,
        )
        for i in range(CLOTH_COLUMNS):  # pin the top row to the board
            for joint in list(spec.body(f"{CLOTH}_{i}").joints):
                spec.delete(joint)
        # MuJoCo's default constraint softness (solref 0.02 s) lets the arm stretch these light
        # edges several-fold when it squeezes the cloth against the board; 2 timesteps keeps
        # them near their length (as for the cable's edges).
        (edges,) = [eq for eq in spec.equalities if eq.type == mujoco.mjtEq.mjEQ_FLEX]
        edges.solref = [2 * spec.option.timestep, 1.0]
        edges.solimp = [0.95, 0.99, 0.001, 0.5, 2.0]
        flex.selfcollide = mujoco.mjtFlexSelf.mjFLEXSELF_NONE
        flex.friction = [CLOTH_FRICTION, 0.005, 0.0001]
        flex.priority = CONTACT_PRIORITY
        flex.solref = list(CONTACT_SOLREF)
        flex.solimp = list(CONTACT_SOLIMP)
        spec.option.solver = SOLVER
        flex.rgba = [0.85, 0.35, 0.3, 1.0]

    def apply_world(self, sim: MujocoBackend, offset: np.ndarray) -> None:
        sim.model.body(BOARD).pos = self.board_nominal_pos + offset

    def reset_objects(self, sim: MujocoBackend) -> None:
        """Nothing to do: the cloth hangs flat and at rest in its build pose (``qpos0``, relative
        to the board), where ``mj_resetData`` already put it."""

    def cloth_points(self, scene: SceneState) -> np.ndarray:
        """World positions of the cloth's grid points (rows top to bottom) (63, 3)."""
        return scene.points(CLOTH)

    def board_corners(self, scene: SceneState) -> np.ndarray:
        pos, rot = scene.geom_pose(BOARD)
        return board_corners(pos, rot, np.array(BOARD_HALF_SIZE))

    def is_success(self, scene: SceneState) -> bool:
        return cloth_on_board(self.cloth_points(scene), self.board_corners(scene))
