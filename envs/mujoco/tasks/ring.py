"""MuJoCo scene of RMB's Ring (:mod:`rmb_lerobot.envs.tasks.ring`): the hook, the pole and the
ring.

The ring is MuJoCo's discrete elastic rod (a 1D flex with bending/twist elasticity and
inextensible edges), curved in its compiled pose so that the circle is its rest shape. MuJoCo 4
supports closed 1D flex loops (``flexcomp type="circle"``), but closed loops carry no per-edge
twist joints, and only those let contact friction act on the tube's rotation about its own axis:
a closed loop pinched by the gripper turns freely about the pinched segment like a bead on a
wire, so it can never be held in a chosen plane. This scene therefore builds the ring as an open
rod of ``num_segments`` edges with twist joints (named as MuJoCo's rod model binds them) whose
last vertex is tied to the first by a ``connect`` equality: a loop that grips like a plastic
ring. The seam is a ball joint (no bending stiffness across it); it is placed at the top vertex,
the one resting on the hook, far from where the ring is gripped.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np

from rmb_lerobot.envs.mujoco.tasks.base import MujocoTaskScene
from rmb_lerobot.envs.tasks.ring import (
    HOOK,
    HOOK_XY,
    PEG1,
    PEG2,
    PEG_HALF_LENGTH,
    PEG_RADIUS,
    PEG_Y,
    POLE,
    POLE_HEIGHT,
    POLE_RADIUS,
    RING,
    RING_MASS,
    SEAM,
    TUBE_RADIUS,
    RingTask,
)

if TYPE_CHECKING:
    from rmb_lerobot.envs.mujoco.backend import MujocoBackend


class RingScene(MujocoTaskScene[RingTask]):
    """The hook, the pole (moved by the world's offset) and the ring as a closed 1D flex rod."""

    def build(self, spec: mujoco.MjSpec, sim: MujocoBackend) -> None:
        spec.option.integrator = mujoco.mjtIntegrator.mjINT_DISCRETE
        hook = spec.worldbody.add_body(name=HOOK, pos=list(self.task.hook_pos))
        for name, y in ((PEG1, PEG_Y[0]), (PEG2, PEG_Y[1])):
            hook.add_geom(
                name=name,
                type=mujoco.mjtGeom.mjGEOM_CYLINDER,
                size=[PEG_RADIUS, PEG_HALF_LENGTH, 0],
                pos=[0, y - HOOK_XY[1], 0],  # RMB's offsets from its hook centre
                quat=[np.cos(np.pi / 4), 0, np.sin(np.pi / 4), 0],  # axis along x
                rgba=[0.8, 0.1, 0.5, 1.0],
            )
        pole = spec.worldbody.add_body(name=POLE, pos=list(self.task.pole_nominal_pos))
        pole.add_geom(
            type=mujoco.mjtGeom.mjGEOM_CYLINDER,
            size=[POLE_RADIUS, POLE_HEIGHT / 2, 0],
            pos=[0, 0, POLE_HEIGHT / 2],
            rgba=[0.1, 0.5, 0.8, 1.0],
        )
        self._build_ring(spec)

    def _build_ring(self, spec: mujoco.MjSpec) -> None:
        """Vertices 0..n-1 on bodies with three slide joints, vertex n on a further body at
        vertex 0's place (the open rod's end), tied to it by the seam; one twist hinge per edge."""
        n = self.task.num_segments
        points = self.task.ring_nominal_points()
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
        flex.young = self.task.young
        flex.damping = self.task.elastic_damping
        flex.selfcollide = mujoco.mjtFlexSelf.mjFLEXSELF_NONE  # a stiff ring cannot fold
        flex.friction = [self.task.friction, 0.005, 0.0001]
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
        sim.model.body(POLE).pos = self.task.pole_nominal_pos + offset

    def reset_objects(self, sim: MujocoBackend) -> None:
        """Nothing to do: the ring starts at rest on the hook in its build pose (``qpos0``),
        where ``mj_resetData`` already put it along with the rod's reference frames."""
