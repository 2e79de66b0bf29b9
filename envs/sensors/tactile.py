"""RMB's MuJoCo fingertip tactile grid, computed in Python from MuJoCo's contacts.

RoboManipBaselines measures fingertip contact with isri-aist's MujocoTactileSensorPlugin (a
C++ sensor plugin; RMB's ``ur5e_tactile_sensor_config.xml``). :class:`TactileGrid` computes
the same reading from ``mjData`` without the plugin:

- **Grid**: ``rows x cols`` points (RMB: 5 x 8) with spacing ``pitch`` (RMB: 4 mm) in the
  x-y plane of a *site*, centred on it: point ``(i, j)`` sits at
  ``x = (i - (rows - 1) / 2) * pitch``, ``y = (j - (cols - 1) / 2) * pitch``, ``z = 0``.
  Row index ``i`` runs along the site's x axis, column ``j`` along its y axis (RMB reshapes the
  plugin's row-major output to ``(5, 8)``). The grid's normal is the site's +z axis.
- **Contacts**: every contact one of whose geoms belongs to the site body's *weld group*
  (the body and every body rigidly attached to it, MuJoCo's ``body_weldid``; for the Robotiq
  2F-85 the pad, its silicone layer and the follower link carrying them) adds to the **nearest**
  grid point. There is no distance cut-off: a contact beyond the grid's edge (e.g. on the
  follower link) lands on the nearest edge point, as in the plugin. Contacts of other bodies
  add nothing.
- **Value**: the contact's force vector (``mj_contactForce``: normal and friction, rotated out
  of the contact frame) projected on the site's +z axis. The force is the one the sensing body
  exerts on the other body, so with +z pointing out of the pad surface (how RMB places its
  UR5e sites) pressing reads **positive**, in newtons.

One documented difference: the plugin reverses the force only when the site's *body* is the
contact's first geom's body, comparing a body id with a weld id; for the 2F-85 pads (which are
not their weld group's root) it never reverses, so its sign follows MuJoCo's geom order
(positive against boxes and meshes, which MuJoCo orders after the pad's box geoms, negative
against spheres, capsules, cylinders and planes). Here the sign never depends on the order.
The plugin's grid readings are the first ``rows * cols`` numbers of its sensor data (the rest
are the fixed grid positions and normals); RMB records only those, as a ``(rows, cols)`` array
named after the sensor (``left_tactile_sensor``, ``right_tactile_sensor``).

MuJoCo-specific (it reads ``mjModel``/``mjData``); :data:`ROBOT_PADS` says where each robot's
pads are and :func:`add_pad_sites` puts their sites into a model spec.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from rmb_lerobot import keys as K

__all__ = [
    "RMB_GRID_SHAPE",
    "RMB_PITCH",
    "ROBOT_PADS",
    "PadSite",
    "TactileGrid",
    "add_pad_sites",
    "pads_for",
]

RMB_GRID_SHAPE = K.TACTILE_SHAPE  # sensor_nums in RMB's ur5e_tactile_sensor_config.xml
RMB_PITCH = 0.004  # sensor_interval (m)


class TactileGrid:
    """A grid of pressure points on a site of a compiled model, read from contacts.

    Parameters
    ----------
    model:
        The compiled model.
    site:
        Name of the site that carries the grid (its x-y plane, its +z the normal).
    shape:
        ``(rows, cols)``: points along the site's x and y axes.
    pitch:
        Distance between neighbouring points (m).
    body:
        The body whose contacts count (with its weld group); default: the site's body.
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        site: str,
        *,
        shape: tuple[int, int] = RMB_GRID_SHAPE,
        pitch: float = RMB_PITCH,
        body: str | None = None,
    ):
        rows, cols = (int(n) for n in shape)
        if rows < 1 or cols < 1:
            raise ValueError(f"tactile grid shape must be two positive ints, got {shape!r}")
        if not pitch > 0:
            raise ValueError(f"tactile grid pitch must be > 0 metres, got {pitch!r}")
        site_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, site)
        if site_id < 0:
            raise ValueError(f"no site named {site!r} in the model for the tactile grid")
        if body is None:
            body_id = int(model.site_bodyid[site_id])
        else:
            body_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, body)
            if body_id < 0:
                raise ValueError(f"no body named {body!r} in the model for tactile site {site!r}")
        self.model = model
        self.site = site
        self.shape = (rows, cols)
        self.pitch = float(pitch)
        self._site_id = site_id
        self._weld = int(model.body_weldid[body_id])
        # Per geom: does it belong to the sensing weld group?
        self._mine = model.body_weldid[model.geom_bodyid] == self._weld
        self.row_offsets = (np.arange(rows) - (rows - 1) / 2) * self.pitch  # along site x
        self.col_offsets = (np.arange(cols) - (cols - 1) / 2) * self.pitch  # along site y
        self._force = np.zeros(6)

    @property
    def points(self) -> np.ndarray:
        """Grid points ``(rows, cols, 3)`` in the site frame."""
        x, y = np.meshgrid(self.row_offsets, self.col_offsets, indexing="ij")
        return np.stack([x, y, np.zeros_like(x)], axis=-1)

    def world_points(self, data: mujoco.MjData) -> np.ndarray:
        """Grid points ``(rows, cols, 3)`` in the world frame at ``data``'s state."""
        rot = data.site_xmat[self._site_id].reshape(3, 3)
        return self.points @ rot.T + data.site_xpos[self._site_id]

    def cell_of(self, local_xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Row and column indices of the grid point nearest to each site-frame ``(x, y)``
        (``(..., 2)``); ties go to the lower index, as in the plugin."""
        local_xy = np.asarray(local_xy, dtype=np.float64)
        rows = np.abs(local_xy[..., 0, None] - self.row_offsets).argmin(axis=-1)
        cols = np.abs(local_xy[..., 1, None] - self.col_offsets).argmin(axis=-1)
        return rows, cols

    def read(self, data: mujoco.MjData) -> np.ndarray:
        """The ``(rows, cols)`` grid of normal forces (N) of ``data``'s contacts.

        Uses the contacts and constraint forces of ``data``'s last forward pass (after
        ``mj_step`` those of the step's last substep, where the plugin computes its reading).
        """
        grid = np.zeros(self.shape)
        ncon = data.ncon
        if ncon == 0:
            return grid
        contact = data.contact
        mine = self._mine[contact.geom[:ncon]]  # (ncon, 2)
        # The sensing body's contacts with anything else (a contact inside the group would
        # push the group against itself: no net force).
        selected = np.flatnonzero(mine[:, 0] != mine[:, 1])
        if selected.size == 0:
            return grid
        forces = np.empty((selected.size, 3))
        for k, index in enumerate(selected):
            mujoco.mj_contactForce(self.model, data, int(index), self._force)
            forces[k] = self._force[:3]
        # Contact frame rows are its axes: world force = frame^T f. It acts on geom 2's body;
        # what the sensing body exerts is that when it is geom 1, its opposite when geom 2.
        frames = contact.frame[selected].reshape(-1, 3, 3)
        world = np.einsum("kij,ki->kj", frames, forces)
        world[~mine[selected, 0]] *= -1.0
        rot = data.site_xmat[self._site_id].reshape(3, 3)  # columns: site axes in the world
        normal_force = world @ rot[:, 2]
        local = (contact.pos[selected] - data.site_xpos[self._site_id]) @ rot
        rows, cols = self.cell_of(local[:, :2])
        np.add.at(grid, (rows, cols), normal_force)
        return grid


@dataclass(frozen=True)
class PadSite:
    """A tactile site to add to a robot model: RMB's data key (the plugin sensor's name), the
    site's name and the pad body it is fixed to, its position (m) and orientation (``quat``,
    ``w x y z``) in that body's frame."""

    key: str
    site: str
    body: str
    pos: tuple[float, float, float]
    quat: tuple[float, float, float, float]


def _euler_x(angle: float) -> tuple[float, float, float, float]:
    return (float(np.cos(angle / 2)), float(np.sin(angle / 2)), 0.0, 0.0)


# RMB's ur5e_integrated_body.xml: on each 2F-85 pad body, pos="0 -0.006 0.01875"
# euler="1.5708 0 0" (radians): the grid's x across the finger, y along it, +z out of the pad's
# gripping face towards the other finger.
_2F85_SITE_POS = (0.0, -0.006, 0.01875)
_2F85_SITE_QUAT = _euler_x(1.5708)


def _2f85_pads(prefix: str) -> tuple[PadSite, ...]:
    return tuple(
        PadSite(
            key=key,
            site=prefix + key,
            body=f"{prefix}{side}_pad",
            pos=_2F85_SITE_POS,
            quat=_2F85_SITE_QUAT,
        )
        for side, key in (("left", K.LEFT_TACTILE_SENSOR), ("right", K.RIGHT_TACTILE_SENSOR))
    )


ROBOT_PADS: dict[str, tuple[PadSite, ...]] = {
    "ur5e": _2f85_pads("gripper/"),
}
"""Robot short name -> its tactile pads (robots RMB gives tactile sensors in MuJoCo)."""


def pads_for(robot: str) -> tuple[PadSite, ...]:
    """The tactile pads of a robot; ``ValueError`` names the robots that have them."""
    try:
        return ROBOT_PADS[robot]
    except KeyError:
        raise ValueError(
            f"robot {robot!r} has no tactile pads; tactile=True works for: "
            f"{', '.join(sorted(ROBOT_PADS))}"
        ) from None


def add_pad_sites(spec: mujoco.MjSpec, pads: tuple[PadSite, ...]) -> None:
    """Add each pad's site (an invisible marker, group 5 as in RMB) to an uncompiled spec."""
    for pad in pads:
        body = spec.body(pad.body)
        if body is None:
            raise ValueError(f"no body {pad.body!r} in the model for tactile site {pad.site!r}")
        body.add_site(
            name=pad.site,
            pos=list(pad.pos),
            quat=list(pad.quat),
            type=mujoco.mjtGeom.mjGEOM_BOX,
            size=[0.005, 0.005, 0.01],
            rgba=[0.1, 0.6, 0.1, 1.0],
            group=5,
        )
