"""MuJoCo scene of RMB's Cloth (:mod:`rmb_lerobot.envs.tasks.cloth`): the board and the cloth
hanging from it.

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
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np

from rmb_lerobot.envs.mujoco.tasks.base import MujocoTaskScene
from rmb_lerobot.envs.tasks.cloth import (
    BOARD,
    BOARD_HALF_SIZE,
    CLOTH,
    CLOTH_COLUMNS,
    CLOTH_FRICTION,
    CLOTH_FROM_BOARD,
    CLOTH_MASS,
    CLOTH_RADIUS,
    CLOTH_ROWS,
    CLOTH_SPACING,
    ClothTask,
)

if TYPE_CHECKING:
    from rmb_lerobot.envs.mujoco.backend import MujocoBackend

# Every cloth contact uses the cloth's contact softness, MuJoCo's default (time constant 20 ms,
# impedance 0.9-0.95), also against the gripper pads, whose own contact (priority 1: time
# constant 4 ms, clamped to 8 ms, impedance 0.95-0.99) matches a touched point's velocity to
# the pad's within one step and flung points at 10-25 m/s under random arm motion.
CONTACT_PRIORITY = 2
CONTACT_SOLREF = (0.02, 1.0)
CONTACT_SOLIMP = (0.9, 0.95, 0.001, 0.5, 2.0)
# MuJoCo 4.0.0's sparse Newton solver can get a wrong Hessian factor (fixed upstream in 4.0.1,
# google-deepmind/mujoco #3767): where the cloth touches both fingers' links, a step diverged
# (cloth points at ~900 m/s, or MuJoCo reset the state on a huge acceleration) in about 1 of
# 30 random-action rollouts; the same states solve correctly with a dense Jacobian (4-8x
# slower) or CG, which never factorises the Hessian. CG costs ~1.3 ms more per env step in
# expert episodes (RESULTS.md). Back to Newton once the project is on MuJoCo >= 4.0.1.
SOLVER = mujoco.mjtSolver.mjSOL_CG


class ClothScene(MujocoTaskScene[ClothTask]):
    """The board (moved by the world's offset) and the cloth, a 2D flex pinned to it."""

    def build(self, spec: mujoco.MjSpec, sim: MujocoBackend) -> None:
        board = spec.worldbody.add_body(
            name=BOARD, pos=list(self.task.board_nominal_pos), quat=list(self.task.board_quat)
        )
        board.add_geom(
            name=BOARD,
            type=mujoco.mjtGeom.mjGEOM_BOX,
            size=list(BOARD_HALF_SIZE),
            rgba=[0.8, 0.8, 0.2, 1.0],
            friction=[self.task.friction, 0.005, 0.0001],
        )
        self._build_cloth(spec, board)

    def _build_cloth(self, spec: mujoco.MjSpec, board: mujoco.MjsBody) -> None:
        """The flex grid in the board frame: grid x (rows) points down, grid y along the
        board's long side, so point ``row * CLOTH_COLUMNS + column`` sits in row ``row``."""
        yaw = self.task.board_yaw
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
        sim.model.body(BOARD).pos = self.task.board_nominal_pos + offset

    def reset_objects(self, sim: MujocoBackend) -> None:
        """Nothing to do: the cloth hangs flat and at rest in its build pose (``qpos0``, relative
        to the board), where ``mj_resetData`` already put it."""
