"""MuJoCo scene of RMB's Cable (:mod:`rmb_lerobot.envs.tasks.cable`): the poles and the cable.

The cable is MuJoCo's discrete elastic rod (a 1D flex with bending/twist elasticity and
inextensible edges), built directly with :class:`mujoco.MjSpec`: MuJoCo 4 removed the
``elasticity.cable`` plugin and ``composite`` in favour of this model. Its first vertex is
pinned to the connector (a ball joint, like RMB's first hinge pair) and its last edge is
clamped inside the end box (RMB welds the box to the last link). Rod elasticity needs MuJoCo's
``discrete`` integrator, so this scene switches to it (the arms' servos stay stable under it
thanks to their joints' armature: see the xArm7 model's ``ARMATURE``). In RMB's ALOHA layout
(:attr:`CablePlacement.free_connector`) the connector box is a free, colliding body instead,
and the worlds move pole 2 by the mirror image of pole 1's shift
(:attr:`CablePlacement.mirror_poles`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np

from rmb_lerobot.envs.mujoco.tasks.base import MujocoTaskScene
from rmb_lerobot.envs.tasks.cable import (
    CABLE,
    CABLE_ANCHOR,
    CABLE_END,
    CABLE_LENGTH,
    CABLE_MASS,
    CABLE_RADIUS,
    END_BOX_HALF_SIZE,
    END_BOX_MASS,
    POLE1,
    POLE2,
    POLE_HALF_HEIGHT,
    POLE_RADIUS,
    POLES,
    CableTask,
)

if TYPE_CHECKING:
    from rmb_lerobot.envs.mujoco.backend import MujocoBackend

_YELLOW = [1.0, 1.0, 0.2, 1.0]


class CableScene(MujocoTaskScene[CableTask]):
    """The two poles (moved by the world's offset) and the cable as a 1D flex rod."""

    def build(self, spec: mujoco.MjSpec, sim: MujocoBackend) -> None:
        spec.option.integrator = mujoco.mjtIntegrator.mjINT_DISCRETE
        self._build_poles(spec)
        self._build_cable(spec)

    def _build_poles(self, spec: mujoco.MjSpec) -> None:
        poles = spec.worldbody.add_body(name=POLES, pos=list(self.task.poles_nominal_pos))
        for name, x in ((POLE1, 0.0), (POLE2, self.task.pole_spacing)):
            poles.add_geom(
                name=name,
                type=mujoco.mjtGeom.mjGEOM_CYLINDER,
                size=[POLE_RADIUS, POLE_HALF_HEIGHT, 0],
                pos=[x, 0, POLE_HALF_HEIGHT],
                rgba=[0.8, 0.0, 0.0, 1.0],
            )

    def _build_cable(self, spec: mujoco.MjSpec) -> None:
        """A 1D flex along -y from the anchor: vertex 0 on the static anchor, vertices 1..n-3
        on bodies with three slide joints, the last two on the free end box (clamped last edge),
        plus one twist hinge per unclamped edge, named as MuJoCo's rod model binds them."""
        n = self.task.num_vertices
        spacing = CABLE_LENGTH / (n - 1)
        direction = np.array([0.0, -1.0, 0.0])
        slide = mujoco.mjtJoint.mjJNT_SLIDE
        vertex_mass = CABLE_MASS / n

        anchor = spec.worldbody.add_body(name=CABLE_ANCHOR, pos=list(self.task.anchor_pos))
        if self.task.free_connector:
            # RMB's ALOHA cable lies loose: its connector box is a free, colliding body, the
            # first vertex on its centre (the first edge turns about it like a ball joint).
            anchor.add_freejoint(name=CABLE_ANCHOR)
            anchor.add_geom(
                type=mujoco.mjtGeom.mjGEOM_BOX,
                size=list(END_BOX_HALF_SIZE),
                quat=[np.cos(np.pi / 4), 0, 0, -np.sin(np.pi / 4)],
                mass=END_BOX_MASS,
                rgba=_YELLOW,
                friction=[1.0, 0.005, 0.0001],
            )
        else:
            anchor.add_geom(  # RMB's connector box at the fixed end (visual only)
                type=mujoco.mjtGeom.mjGEOM_BOX,
                size=list(END_BOX_HALF_SIZE),
                quat=[np.cos(np.pi / 4), 0, 0, -np.sin(np.pi / 4)],
                rgba=_YELLOW,
                contype=0,
                conaffinity=0,
            )
        bodies, verts = [CABLE_ANCHOR], [[0.0, 0.0, 0.0]]
        inertia = [vertex_mass * 1e-4] * 3  # point masses; MuJoCo needs a rotational inertia
        for i in range(1, n - 2):
            body = spec.worldbody.add_body(
                name=f"{CABLE}_{i}",
                pos=list(self.task.anchor_pos + i * spacing * direction),
                mass=vertex_mass,
                inertia=inertia,
            )
            for axis in np.eye(3):
                body.add_joint(type=slide, axis=list(axis))
            bodies.append(body.name)
            verts.append([0.0, 0.0, 0.0])

        end = spec.worldbody.add_body(
            name=CABLE_END,
            pos=list(self.task.anchor_pos + CABLE_LENGTH * direction),
            quat=[np.cos(np.pi / 4), 0, 0, -np.sin(np.pi / 4)],  # box x axis along the cable
        )
        end.add_freejoint(name=CABLE_END)
        end.add_geom(
            type=mujoco.mjtGeom.mjGEOM_BOX,
            size=list(END_BOX_HALF_SIZE),
            mass=END_BOX_MASS,
            rgba=_YELLOW,
            friction=[1.0, 0.005, 0.0001],
        )
        bodies += [CABLE_END, CABLE_END]
        verts += [[-spacing, 0.0, 0.0], [0.0, 0.0, 0.0]]

        edges = n - 1
        edge_inertia = 0.5 * (CABLE_MASS / edges) * CABLE_RADIUS**2
        for e in range(edges - 1):  # the last edge is clamped in the end box: no twist joint
            name = f"{CABLE}_twist_{e}"
            twist = spec.worldbody.add_body(name=name, mass=1e-9, inertia=[edge_inertia] * 3)
            twist.add_joint(name=name, type=mujoco.mjtJoint.mjJNT_HINGE, axis=[1, 0, 0])

        flex = spec.add_flex()
        flex.name = CABLE
        flex.dim = 1
        flex.radius = CABLE_RADIUS
        flex.vertbody = bodies
        flex.vert = np.asarray(verts, dtype=np.float64).ravel().tolist()
        flex.elem = [v for e in range(edges) for v in (e, e + 1)]
        flex.young = self.task.young
        flex.damping = self.task.elastic_damping
        flex.selfcollide = mujoco.mjtFlexSelf.mjFLEXSELF_AUTO  # a cable cannot pass itself
        flex.friction = [self.task.friction, 0.005, 0.0001]
        flex.rgba = [0.9, 0.9, 0.9, 1.0]
        # Inextensible edges. MuJoCo's default constraint softness (solref 0.02 s) lets these
        # light vertices stretch ~15 % under a 1 N pull; 2 timesteps keeps it under 2 %.
        spec.add_equality(
            type=mujoco.mjtEq.mjEQ_FLEX,
            name1=CABLE,
            solref=[2 * spec.option.timestep, 1.0],
            solimp=[0.95, 0.99, 0.001, 0.5, 2.0],
        )

    def apply_world(self, sim: MujocoBackend, offset: np.ndarray) -> None:
        sim.model.body(POLES).pos = self.task.poles_nominal_pos + offset
        if self.task.mirror_poles:
            sim.model.geom(POLE2).pos[0] = self.task.pole2_local_x(self.task.world_idx)

    def reset_objects(self, sim: MujocoBackend) -> None:
        """Nothing to do: the cable starts straight and at rest in its build pose (``qpos0``),
        where ``mj_resetData`` already put it along with the rod's reference frames."""
