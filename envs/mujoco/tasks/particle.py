"""MuJoCo scene of RMB's Particle (:mod:`rmb_lerobot.envs.tasks.particle`): the two containers,
the scoop and the particles.

MuJoCo's sleeping is on: particles at rest drop out of the simulation until something touches
them (the robot, which is actuated, never sleeps), which makes the scene several times faster
while they rest.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np

from rmb_lerobot.envs.mujoco.tasks.base import MujocoTaskScene
from rmb_lerobot.envs.tasks.particle import (
    CASE_CENTRE_BELOW_TABLE,
    CASE_HEIGHT,
    CASE_WALL_HALF_THICKNESS,
    GOAL,
    GOAL_HALF_SIDE,
    HANDLE_HALF,
    HANDLE_POS,
    PARTICLE,
    PARTICLE_RADIUS,
    SCOOP,
    SCOOP_FRICTION,
    SCOOP_HANDLE,
    SCOOP_PLATE_HALF,
    SCOOP_WALL_HEIGHT,
    SOURCE,
    SOURCE_HALF_SIDE,
    ParticleTask,
)

if TYPE_CHECKING:
    from rmb_lerobot.envs.mujoco.backend import MujocoBackend

_SOURCE_RGBA = [0.8, 0.1, 0.5, 1.0]
_GOAL_RGBA = [0.1, 0.5, 0.8, 1.0]
_SCOOP_RGBA = [0.1, 0.8, 0.1, 1.0]
_PARTICLE_RGBA = [0.8, 0.8, 0.2, 1.0]


def _add_case(
    parent: mujoco.MjsBody,
    name: str,
    pos: np.ndarray,
    half_side: float,
    rgba: list[float],
    mocap: bool = False,
) -> None:
    """Four walls around a square (RMB's ``*_case`` bodies, walls ``<name>_px`` etc.); from
    the table top 4 cm up (RMB's walls also reach 4 cm into the table, where nothing sees
    them)."""
    body = parent.add_body(name=name, pos=list(pos), mocap=mocap)
    length = half_side + CASE_WALL_HALF_THICKNESS
    wall_z = CASE_CENTRE_BELOW_TABLE + CASE_HEIGHT / 2
    for suffix, xy, size in (
        ("px", (half_side, 0.0), (CASE_WALL_HALF_THICKNESS, length)),
        ("nx", (-half_side, 0.0), (CASE_WALL_HALF_THICKNESS, length)),
        ("py", (0.0, half_side), (length, CASE_WALL_HALF_THICKNESS)),
        ("ny", (0.0, -half_side), (length, CASE_WALL_HALF_THICKNESS)),
    ):
        body.add_geom(
            name=f"{name}_{suffix}",
            type=mujoco.mjtGeom.mjGEOM_BOX,
            size=[*size, CASE_HEIGHT / 2],
            pos=[*xy, wall_z],
            rgba=rgba,
        )


def _add_scoop(parent: mujoco.MjsBody, pos: np.ndarray) -> None:
    """RMB's scoop: plate, back and side walls, and the handle (boxes, default density)."""
    box = mujoco.mjtGeom.mjGEOM_BOX
    scoop = parent.add_body(name=SCOOP, pos=list(pos))
    scoop.add_freejoint(name=SCOOP)
    px, py, pz = SCOOP_PLATE_HALF
    wall = SCOOP_WALL_HEIGHT / 2
    for size, wall_pos in (
        ((px, py, pz), (0.0, 0.0, 0.0)),  # plate
        ((0.002, py, wall), (-0.04, 0.0, wall)),  # back wall
        ((px, 0.001, wall), (0.0, 0.04, wall)),  # side walls
        ((px, 0.001, wall), (0.0, -0.04, wall)),
    ):
        scoop.add_geom(
            type=box,
            size=list(size),
            pos=list(wall_pos),
            rgba=_SCOOP_RGBA,
            friction=[SCOOP_FRICTION, 0.005, 0.0001],
        )
    scoop.add_geom(
        name=SCOOP_HANDLE, type=box, size=list(HANDLE_HALF), pos=list(HANDLE_POS),
        rgba=_SCOOP_RGBA,
    )  # fmt: skip


class ParticleScene(MujocoTaskScene[ParticleTask]):
    """The containers (the source a mocap body moved by the world's offset), scoop, particles."""

    def __init__(self, task: ParticleTask) -> None:
        super().__init__(task)
        # (id(model), particle body ids, their first qpos and dof addresses), on first use.
        self._particle_ids: tuple[int, np.ndarray, np.ndarray, np.ndarray] | None = None

    def build(self, spec: mujoco.MjSpec, sim: MujocoBackend) -> None:
        # Resting particles (and the scoop) sleep until something awake touches them.
        spec.option.enableflags |= int(mujoco.mjtEnableBit.mjENBL_SLEEP)
        # Coarser sphere meshes (MuJoCo's default 28 x 16 makes the 30 particles cost as many
        # triangles as the robot): a quarter less render time, images within 0.2 grey levels.
        spec.visual.quality.numslices = 12
        spec.visual.quality.numstacks = 8
        world = spec.worldbody
        # A mocap body, so that a world shift applied after mj_resetData reaches the walls:
        # with sleeping on, MuJoCo computes static bodies' poses only when it resets.
        _add_case(world, SOURCE, self.task.source_nominal_pos, SOURCE_HALF_SIDE, _SOURCE_RGBA, True)
        _add_case(world, GOAL, self.task.goal_pos, GOAL_HALF_SIDE, _GOAL_RGBA)
        _add_scoop(world, self.task.scoop_pos)
        for i, pos in enumerate(self.task.particle_start_positions(self.task.source_nominal_pos)):
            body = world.add_body(name=f"{PARTICLE}_{i}", pos=list(pos))
            for axis in np.eye(3):
                body.add_joint(type=mujoco.mjtJoint.mjJNT_SLIDE, axis=list(axis))
            body.add_geom(
                type=mujoco.mjtGeom.mjGEOM_SPHERE,
                size=[PARTICLE_RADIUS, 0, 0],
                rgba=_PARTICLE_RGBA,
                friction=[self.task.particle_friction, 0.005, 0.0001],
            )

    def apply_world(self, sim: MujocoBackend, offset: np.ndarray) -> None:
        sim.model.body(SOURCE).pos = self.task.source_nominal_pos + offset

    def _ids(self, model: mujoco.MjModel) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Particle body ids and the qpos and dof addresses of their x slide joints (the y
        and z joints follow)."""
        if self._particle_ids is None or self._particle_ids[0] != id(model):
            bodies = np.array([model.body(name).id for name in self.task.particle_names])
            joints = model.body_jntadr[bodies]
            self._particle_ids = (
                id(model),
                bodies,
                model.jnt_qposadr[joints],
                model.jnt_dofadr[joints],
            )
        return self._particle_ids[1:]

    def reset_objects(self, sim: MujocoBackend) -> None:
        """The scoop on the table at its place, the particles at rest in their block, moved
        with the source container (their slide joints hold the world's shift)."""
        model, data = sim.model, sim.data
        source = model.body(SOURCE)
        data.mocap_pos[source.mocapid[0]] = source.pos
        scoop = data.joint(SCOOP)
        scoop.qpos[:3] = self.task.scoop_pos
        scoop.qpos[3:] = (1.0, 0.0, 0.0, 0.0)
        scoop.qvel[:] = 0.0
        _, qpos, dofs = self._ids(model)
        shift = source.pos - self.task.source_nominal_pos
        for axis in range(3):
            data.qpos[qpos + axis] = shift[axis]
            data.qvel[dofs + axis] = 0.0
