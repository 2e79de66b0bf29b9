"""DIGIT-like fingertip tactile images in PyBullet, without the ``tacto`` package.

RMB's TACTO envs record one RGB image per fingertip (``tactile_left_rgb_image``,
``tactile_right_rgb_image``, 480 x 640 H x W). TACTO sums the normal forces of the sensor
link's contacts with the bodies registered with it, moves each touching body towards the sensor
by ``min(F, 100) / 100 * 0.005`` m and renders what then lies in front of the gel with pyrender.
Here the same rule is applied to a *gap map* measured with PyBullet rays, and the shading is
:mod:`rmb_lerobot.envs.sensors.digit`'s:

1. **Force** per tactile body: the sum of ``getContactPoints(bodyA=robot, linkIndexA=link)``
   normal forces (``pt[9]``) with that body; bodies outside ``tactile_bodies`` are ignored, as
   TACTO ignores bodies not added to the sensor.
2. **Gap map**: a coarse grid of rays (default 24 x 32 per pad) along the pad's outward normal,
   from ``behind`` (2 mm) inside the pad to ``reach`` (8 mm) outside the gel surface;
   ``gap = hit distance - behind`` (negative where a body penetrates the pad). Bullet's ray
   test on convex shapes (``btGjkConvexCast``) reports a hit as soon as the ray comes within
   1 mm of a shape, and a ray that starts within 1 mm of one (inside or out) "hits" it at
   fraction 0; deeper inside a box it reports nothing. Hence (all measured here):

   - a ray whose first hit is not a tactile body (the robot's own pad, the other finger, the
     table) is cast again past it, up to ``max_recasts`` times, jumping 1.1 mm when stuck at
     fraction 0;
   - every tactile hit that can matter is cast a second time from 1.2 mm before it, which cuts
     the early-hit error on curved faces 2.5-4x (:func:`_refine`); planar faces are exact;
   - the outer ring of rays (0.4 mm from the pad box's side faces) starts stuck on the pad, so
     objects within about 1.3 mm of the gel there are not seen: a contact reaching the gel's
     edge fades out over its outer 0.5-1 mm;
   - an object pressed more than ``behind - 1 mm`` (1 mm) into the pad reads as ``-behind``.
3. **Indentation**: per ray ``c = push(F_body) - gap`` (rays that hit nothing, or a tactile
   body without contact force, get ``-floor``), clamped below at ``-floor`` (1 mm) so a missed
   ray is not a cliff for the interpolation; ``c`` is upsampled to the image with separable
   Catmull-Rom interpolation (:func:`upsample`) and ``h = max(0, c)`` is taken at full
   resolution, so a sphere's disc keeps a sharp, accurate rim even from a coarse grid.
4. :class:`~rmb_lerobot.envs.sensors.digit.DigitSensorImage` shades ``h``.

Pad geometry (:class:`PadSpec`, in the fingertip link's URDF frame): the gel face's centre,
outward unit normal, the in-plane ``along`` axis (towards the fingertip) and the gel size
(default TACTO's 0.02 m across x 0.03 m along); ``across`` follows. The link's collision shape
must hold every ray start more than 1 mm from its other faces, i.e. reach at least
``behind + 1 mm`` (3 mm by default) behind the gel face, or every ray starts stuck on the pad
(a 2 mm pad with ``behind = 2 mm`` gave a disc twice as deep; a 3 mm pad worked with
``behind = 1.2 mm``; ``behind`` itself must stay above 1 mm). RMB's DIGIT pad box in
:mod:`rmb_lerobot.envs.pybullet.sawyer` is 4 mm thick, its gel face at ``PAD_CENTRE`` with
normal link +x and ``along`` link +z:
``PadSpec(link, PAD_CENTRE, (1, 0, 0), (0, 0, 1))`` (``across`` is then link -y).

Image orientation (shared with :mod:`rmb_lerobot.envs.sensors.digit`): the image is what a
camera inside the sensor sees looking out along the pad's outward ``normal``; image columns run
along ``PadSpec.along`` (left to right), image rows along ``PadSpec.across`` (top to bottom), and
``along x across = normal`` (right-handed, checked). For two pads facing each other across a
mirror plane (a parallel gripper; RMB's right finger frame is the left one turned by pi about
the finger axis) both ``across`` axes then point opposite ways in the world, so the right image
is the left one flipped upside down (``right[::-1]``): the *geometry* (indentation map, disc
positions) is an exact mirror image. The shading keeps each sensor's own light layout (red at 30
degrees on screen), as two identical DIGITs would and TACTO does, so colours are not flipped.

Timings here (2 cores shared with other jobs, load average about 7, so wall times vary 2x;
median CPU time of 40 calls, two 480 x 640 pads squeezing a 1 cm sphere at 10 N): rays 6-11 ms
(about 1900 rays: 2 x 768, the recast outer rings and the refinement; 2-4 us a ray in
``rayTestBatch``), the whole render 12-19 ms without noise and 18-25 ms with it (best wall
times 9-12 and 21-26 ms); no contact costs no rays (5-8 ms, the noise). Grids: 16 x 24 rays
4-6 ms, 32 x 48 18 ms, 48 x 64 25-39 ms.
"""

from __future__ import annotations

import functools
import operator
from collections.abc import Collection, Sequence
from dataclasses import dataclass, field

import numpy as np
import pybullet as p

from rmb_lerobot.envs.sensors.digit import DigitConfig, DigitSensorImage, push_depth

__all__ = [
    "DEFAULT_GRID",
    "PadReading",
    "PadSpec",
    "RayOptions",
    "TactilePads",
    "link_pose",
    "pad_forces",
    "render_pad",
    "upsample",
]

Vec3 = tuple[float, float, float]

#: Rays per pad (rows along ``across``, columns along ``along``): 768 rays, 0.83 x 0.94 mm apart
#: on TACTO's 0.02 x 0.03 m gel, about 3 ms per pad here; finer grids cost proportionally more.
DEFAULT_GRID: tuple[int, int] = (24, 32)

_GJK_RADIUS = 0.001  # btGjkConvexCast: a ray "hits" once it is this close to a convex shape
_REFINE_BACKOFF = 0.0012  # > 1 mm: a cast from within 1 mm of a face reports fraction 0
_REFINE_AHEAD = 0.001  # hits come at most 1 mm early
_BODY = operator.itemgetter(0)  # rayTestBatch result: (body, link, fraction, position, normal)
_FRACTION = operator.itemgetter(2)
_MAX_BATCH = 16384  # pybullet's rayTestBatch limit (20000 rays: "exceed the maximum batch size")


def _unit(v: Sequence[float], name: str) -> np.ndarray:
    a = np.asarray(v, dtype=np.float64)
    if a.shape != (3,):
        raise ValueError(f"pad {name} must be 3 numbers, got {v!r}")
    n = float(np.linalg.norm(a))
    if n < 1e-9:
        raise ValueError(f"pad {name} must not be zero")
    return a / n


@dataclass(frozen=True)
class PadSpec:
    """Where a gel pad is on a robot link, in that link's URDF frame.

    Attributes:
        link: Link index on the robot body (-1 for the base).
        center: Centre of the gel's contact face (the undeformed gel surface), metres.
        normal: Outward normal of the face (pointing at the objects it touches).
        along: In-plane axis along the finger (towards its tip): image columns.
        across: In-plane axis across the finger: image rows. Default ``normal x along``, the
            only right-handed choice (``along x across = normal``); a given one must match it.
        gel_across: Gel extent along ``across``, metres (TACTO's DIGIT: 0.02).
        gel_along: Gel extent along ``along``, metres (TACTO's DIGIT: 0.03).

    The link's collision shape should reach at least ``RayOptions.behind + 1 mm`` (3 mm by
    default) behind the gel face: rays start inside it (module docstring).

    Raises:
        ValueError: On a zero or malformed axis, ``along`` not perpendicular to ``normal``, a
            left-handed or skew ``across``, or a non-positive gel size.
    """

    link: int
    center: Vec3
    normal: Vec3
    along: Vec3
    across: Vec3 | None = None
    gel_across: float = 0.02
    gel_along: float = 0.03

    def __post_init__(self) -> None:
        normal = _unit(self.normal, "normal")
        along = _unit(self.along, "along")
        if abs(float(normal @ along)) > 1e-6:
            raise ValueError(f"pad along {self.along} is not perpendicular to normal {self.normal}")
        across = np.cross(normal, along)
        if self.across is not None and not np.allclose(
            _unit(self.across, "across"), across, atol=1e-6
        ):
            raise ValueError(
                f"pad across {self.across} must be normal x along = {tuple(across)} (right-handed:"
                " along x across = normal), so that mirrored pads give mirrored images"
            )
        if not (self.gel_across > 0 and self.gel_along > 0):
            raise ValueError("pad gel size must be positive")
        center = np.asarray(self.center, dtype=np.float64)
        if center.shape != (3,):
            raise ValueError(f"pad center must be 3 numbers, got {self.center!r}")
        object.__setattr__(self, "center", tuple(float(x) for x in center))
        object.__setattr__(self, "normal", tuple(float(x) for x in normal))
        object.__setattr__(self, "along", tuple(float(x) for x in along))
        object.__setattr__(self, "across", tuple(float(x) for x in across))

    def grid_points(self, grid: tuple[int, int]) -> np.ndarray:
        """Ray origins on the gel surface, ``(rows * cols, 3)`` in the link frame.

        Cell centres of a ``rows x cols`` split of the gel, row-major; row ``i`` sits at
        ``((i + 0.5) / rows - 0.5) * gel_across`` along ``across``, column ``j`` at
        ``((j + 0.5) / cols - 0.5) * gel_along`` along ``along`` (the pixel-centre convention
        of ``cv2.resize``, so the upsampled map lines up with the image).
        """
        rows, cols = grid
        a = ((np.arange(rows) + 0.5) / rows - 0.5) * self.gel_across
        b = ((np.arange(cols) + 0.5) / cols - 0.5) * self.gel_along
        aa, bb = np.meshgrid(a, b, indexing="ij")
        pts = (
            np.asarray(self.center)
            + aa.reshape(-1, 1) * np.asarray(self.across)
            + bb.reshape(-1, 1) * np.asarray(self.along)
        )
        return pts


@dataclass(frozen=True)
class RayOptions:
    """How the gap map is measured.

    Attributes:
        grid: Rays per pad ``(rows, cols)``; None is :data:`DEFAULT_GRID`, or the image size
            when the image is smaller.
        behind: Where rays start, metres inside the pad behind the gel surface (> 1 mm:
            Bullet reports an object within 1 mm of a ray's start at the start); objects that
            penetrate the pad up to ``behind - 1 mm`` are measured.
        reach: How far out of the gel surface rays go, metres; must exceed the largest push
            (``DigitConfig.max_push``, 5 mm) so an object at full push is seen.
        floor: Clearance given to rays without a touching body (metres, > 0).
        max_recasts: Times a ray is cast again past a non-tactile body.
        num_threads: ``rayTestBatch``'s ``numThreads`` (1: no threads; 0: Bullet decides).
            Threads helped at 2000 rays and hurt at 4800 on this loaded 2-core machine.
        refine: Cast each tactile hit a second time from close by, for accurate curved faces
            (see :func:`_refine`; costs one more ray per hit).
    """

    grid: tuple[int, int] | None = None
    behind: float = 0.002
    reach: float = 0.008
    floor: float = 0.001
    max_recasts: int = 3
    num_threads: int = 1
    refine: bool = True

    def grid_for(self, cfg: DigitConfig) -> tuple[int, int]:
        """The ray grid used for images of ``cfg``."""
        if self.grid is not None:
            return (int(self.grid[0]), int(self.grid[1]))
        return (min(DEFAULT_GRID[0], cfg.height), min(DEFAULT_GRID[1], cfg.width))


@dataclass
class PadReading:
    """One pad's measurement (what :meth:`TactilePads.read` returns per pad).

    Attributes:
        forces: Normal force per touching tactile body id, newtons.
        gap: Coarse gap map ``(rows, cols)`` in metres (+inf where no tactile body was hit);
            None when nothing touched the pad (no rays were cast).
        indentation: ``(height, width)`` indentation in metres (zeros when nothing touched).
        image: ``(height, width, 3)`` uint8 RGB.
    """

    forces: dict[int, float]
    gap: np.ndarray | None
    indentation: np.ndarray
    image: np.ndarray
    force: float = field(init=False)

    def __post_init__(self) -> None:
        self.force = float(sum(self.forces.values()))


@functools.cache
def _catmull_rom(n: int, m: int) -> tuple[np.ndarray, np.ndarray]:
    """Taps ``(m, 4)`` and weights ``(m, 4)`` that resample ``n`` cell centres to ``m``.

    Cell centres on both sides (``cv2.resize``'s convention): output ``i`` sits at input
    coordinate ``(i + 0.5) * n / m - 0.5``; taps beyond the ends repeat the edge sample.
    """
    x = (np.arange(m) + 0.5) * n / m - 0.5
    i = np.floor(x).astype(np.int64)
    t = (x - i)[:, None]
    t2, t3 = t * t, t * t * t
    w = np.concatenate(
        [
            (-t3 + 2 * t2 - t) / 2,
            (3 * t3 - 5 * t2 + 2) / 2,
            (-3 * t3 + 4 * t2 + t) / 2,
            (t3 - t2) / 2,
        ],
        axis=1,
    ).astype(np.float32)
    taps = np.clip(i[:, None] + np.arange(-1, 3), 0, n - 1)
    taps.flags.writeable = False
    w.flags.writeable = False
    return taps, w


def upsample(
    coarse: np.ndarray,
    shape: tuple[int, int],
    rows: slice | None = None,
    cols: slice | None = None,
) -> np.ndarray:
    """Separable Catmull-Rom resampling of a 2-D map (float32), numpy only.

    Catmull-Rom reproduces quadratics, so a sphere's clearance (locally a paraboloid) comes
    back nearly exact: from a 24 x 32 grid, a 1 cm sphere pushed 1 mm gives images within 2
    counts of the full-resolution ones, against 71 counts with ``cv2.resize``'s bicubic
    (``a = -0.75``, which does not) and 19 with a global cubic spline (it rings at the clamp).
    1.5 ms for all of 480 x 640 here; no BLAS (a matrix product took 0.4 ms alone but 24 ms
    median when OpenBLAS threads met a loaded machine).

    Args:
        coarse: ``(rows, cols)`` samples at cell centres.
        shape: Output ``(height, width)``.
        rows: Only these output rows (default all).
        cols: Only these output columns (default all).

    Returns:
        The ``(height, width)`` map, or its ``[rows, cols]`` part, float32.
    """
    c = np.asarray(coarse, dtype=np.float32)
    rows = rows if rows is not None else slice(0, shape[0])
    cols = cols if cols is not None else slice(0, shape[1])
    row_taps, row_w = _catmull_rom(c.shape[0], shape[0])
    col_taps, col_w = _catmull_rom(c.shape[1], shape[1])
    row_taps, row_w, col_taps, col_w = row_taps[rows], row_w[rows], col_taps[cols], col_w[cols]
    by_row = np.einsum("mt,mtn->mn", row_w, c[row_taps])
    out = by_row[:, col_taps[:, 0]] * col_w[:, 0]
    for t in range(1, 4):
        out += by_row[:, col_taps[:, t]] * col_w[:, t]
    return out


def _reach(active: np.ndarray, m: int) -> slice | None:
    """Output pixels (of ``m``) whose Catmull-Rom taps touch an active coarse cell."""
    cells = np.flatnonzero(active)
    if cells.size == 0:
        return None
    taps, _ = _catmull_rom(active.size, m)
    hit = np.flatnonzero((taps[:, 3] >= cells[0]) & (taps[:, 0] <= cells[-1]))
    return slice(int(hit[0]), int(hit[-1]) + 1)


def link_pose(client: int, body: int, link: int) -> tuple[np.ndarray, np.ndarray]:
    """World pose of a link's URDF frame (not its inertial frame).

    Args:
        client: PyBullet physics client id.
        body: Body unique id.
        link: Link index, -1 for the base.

    Returns:
        ``(position (3,), rotation matrix (3, 3))``.
    """
    if link == -1:
        pos, orn = p.getBasePositionAndOrientation(body, physicsClientId=client)
        info = p.getDynamicsInfo(body, -1, physicsClientId=client)
        inv_pos, inv_orn = p.invertTransform(info[3], info[4])
        pos, orn = p.multiplyTransforms(pos, orn, inv_pos, inv_orn)
    else:
        state = p.getLinkState(body, link, computeForwardKinematics=True, physicsClientId=client)
        pos, orn = state[4], state[5]
    rot = np.asarray(p.getMatrixFromQuaternion(orn), dtype=np.float64).reshape(3, 3)
    return np.asarray(pos, dtype=np.float64), rot


def pad_forces(
    client: int, robot: int, link: int, tactile_bodies: Collection[int]
) -> dict[int, float]:
    """Normal force on a link per tactile body, from the last step's contact points (TACTO).

    Args:
        client: PyBullet physics client id.
        robot: The robot's body id.
        link: The fingertip link index.
        tactile_bodies: Body ids the sensor sees (RMB registers only some bodies with tacto).

    Returns:
        ``{body id: summed normal force (N)}`` for the tactile bodies in contact (> 0 N).
    """
    forces: dict[int, float] = {}
    for pt in p.getContactPoints(bodyA=robot, linkIndexA=link, physicsClientId=client):
        body = pt[2]
        if body in tactile_bodies and body != robot:
            forces[body] = forces.get(body, 0.0) + float(pt[9])
    return {b: f for b, f in forces.items() if f > 0.0}


def _ray_batch(
    client: int, starts: np.ndarray, ends: np.ndarray, num_threads: int
) -> tuple[np.ndarray, np.ndarray]:
    """Body id (-1: none) and hit fraction of each ray, in chunks of pybullet's batch limit.

    Plain lists go in: passing numpy arrays made ``rayTestBatch`` 2-8x slower here.
    """
    bodies = np.empty(len(starts), dtype=np.int64)
    fracs = np.empty(len(starts), dtype=np.float64)
    for lo in range(0, len(starts), _MAX_BATCH):
        hi = min(lo + _MAX_BATCH, len(starts))
        res = p.rayTestBatch(
            starts[lo:hi].tolist(),
            ends[lo:hi].tolist(),
            numThreads=num_threads,
            physicsClientId=client,
        )
        bodies[lo:hi] = np.fromiter(map(_BODY, res), dtype=np.int64, count=hi - lo)
        fracs[lo:hi] = np.fromiter(map(_FRACTION, res), dtype=np.float64, count=hi - lo)
    return bodies, fracs


def _cast_rays(
    client: int,
    starts: np.ndarray,
    dirs: np.ndarray,
    length: float,
    tactile: np.ndarray,
    opts: RayOptions,
    refine_within: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """First tactile body along each ray and its distance from the ray's start.

    Rays whose first hit is another body are cast again from just past that hit: 1e-5 m, or
    1.1 mm when Bullet reports the hit at the very start. Bullet does that for any start
    within 1 mm of a convex shape (inside or out; e.g. the outer ring of rays, 0.4 mm from the
    pad box's side faces), and a start less than 1 mm further would report the same again.
    Objects within about 1.3 mm of the gel there are therefore not seen.

    Args:
        client: PyBullet physics client id.
        starts: Ray starts ``(n, 3)``, world frame.
        dirs: Unit ray directions ``(n, 3)``.
        length: Ray length, metres.
        tactile: Body ids that count as hits.
        opts: Recast and refinement settings.
        refine_within: Per ray, the distance from its start up to which a hit is refined
            (beyond it the hit cannot indent the gel).

    Returns:
        ``(body id or -1 (n,), distance (n,) in metres, +inf where no tactile body)``.
    """
    n = len(starts)
    body = np.full(n, -1, dtype=np.int64)
    dist = np.full(n, np.inf)
    offset = np.zeros(n)
    todo = np.arange(n)
    ends = starts + dirs * length
    for _ in range(opts.max_recasts + 1):
        if todo.size == 0:
            break
        frm = starts[todo] + dirs[todo] * offset[todo, None]
        hit, frac = _ray_batch(client, frm, ends[todo], opts.num_threads)
        along = offset[todo] + frac * (length - offset[todo])
        mine = np.isin(hit, tactile)
        body[todo[mine]] = hit[mine]
        dist[todo[mine]] = along[mine]
        other = (hit >= 0) & ~mine
        stuck = frac * (length - offset[todo]) < 1e-7
        offset[todo] = along + np.where(stuck, _GJK_RADIUS + 1e-4, 1e-5)
        todo = todo[other & (offset[todo] < length)]
    if opts.refine:
        _refine(client, starts, dirs, body, dist, refine_within, opts.num_threads)
    return body, dist


def _refine(
    client: int,
    starts: np.ndarray,
    dirs: np.ndarray,
    body: np.ndarray,
    dist: np.ndarray,
    within: np.ndarray,
    num_threads: int,
) -> None:
    """Casts every tactile hit again from :data:`_REFINE_BACKOFF` before it (in place).

    Bullet's ray test on a convex shape advances along the ray until it is within 1 mm of the
    surface (``btGjkConvexCast``'s ``radius = 0.001``), so a hit on a curved face comes early:
    on a 1 cm sphere, from 2 mm away, 6 um early at 2 mm off the contact point, 40 um at 5 mm.
    One step of that advancement ends on the tangent plane, about ``D**2 tan**2(angle) / 2R``
    off for a start at distance ``D``, so a second cast from 1.2 mm before the first hit cuts
    the error 2.5-4x (2.4 and 17 um at those points; measured). Planar faces are exact either
    way. The later of the two distances is kept (hits only ever come early); a second cast that
    starts within 1 mm of a face reports fraction 0 and is ignored.
    """
    idx = np.flatnonzero((body >= 0) & (dist > 0.0) & (dist <= within))
    if idx.size == 0:
        return
    back = dist[idx] - _REFINE_BACKOFF
    frm = starts[idx] + dirs[idx] * back[:, None]
    to = starts[idx] + dirs[idx] * (dist[idx] + _REFINE_AHEAD)[:, None]
    hit, frac = _ray_batch(client, frm, to, num_threads)
    again = back + frac * (_REFINE_BACKOFF + _REFINE_AHEAD)
    ok = (hit == body[idx]) & (frac > 0.0)
    dist[idx[ok]] = np.maximum(dist[idx[ok]], again[ok])


class TactilePads:
    """Renders several pads of one robot (e.g. the two fingertips) with one ray batch.

    Args:
        client: PyBullet physics client id.
        robot: The robot's body id (its hits never count).
        pads: The pads, in the order images are returned (e.g. left, right).
        tactile_bodies: Body ids the sensors see; may be changed later with
            :meth:`set_tactile_bodies`.
        cfg: Image config (default RMB's 480 x 640). Each pad's gel size replaces ``cfg``'s.
        rays: Ray grid and reach.

    Raises:
        ValueError: If ``rays.reach`` does not exceed ``cfg.max_push``, ``rays.behind`` is not
            above 1 mm, ``rays.floor`` is not positive or the grid is empty.
    """

    def __init__(
        self,
        client: int,
        robot: int,
        pads: Sequence[PadSpec],
        tactile_bodies: Collection[int],
        cfg: DigitConfig | None = None,
        rays: RayOptions | None = None,
    ):
        self.client = int(client)
        self.robot = int(robot)
        self.pads = tuple(pads)
        self.cfg = cfg if cfg is not None else DigitConfig()
        self.rays = rays if rays is not None else RayOptions()
        if not self.rays.reach > self.cfg.max_push:
            raise ValueError(
                f"ray reach {self.rays.reach} m must exceed the largest push {self.cfg.max_push} m"
            )
        if not (self.rays.behind > _GJK_RADIUS and self.rays.floor > 0):
            # A ray starting within 1 mm of an object reports it at fraction 0: objects
            # touching the gel would all read as pressed in by ``behind``.
            raise ValueError(
                f"ray behind must exceed Bullet's 1 mm ray tolerance and floor must be > 0, got "
                f"behind={self.rays.behind}, floor={self.rays.floor}"
            )
        self.grid = self.rays.grid_for(self.cfg)
        if min(self.grid) < 1:
            raise ValueError(f"ray grid must be positive, got {self.grid}")
        self.set_tactile_bodies(tactile_bodies)
        self._sensors = [
            DigitSensorImage(self.cfg.with_gel(pad.gel_across, pad.gel_along)) for pad in self.pads
        ]
        # Ray starts and directions in each link frame (constant).
        self._local = [
            (
                pad.grid_points(self.grid) - self.rays.behind * np.asarray(pad.normal),
                np.asarray(pad.normal),
            )
            for pad in self.pads
        ]

    def set_tactile_bodies(self, tactile_bodies: Collection[int]) -> None:
        """Replaces the set of bodies the sensors see (the robot itself never counts)."""
        self.tactile_bodies = frozenset(int(b) for b in tactile_bodies) - {self.robot}
        self._tactile = np.fromiter(sorted(self.tactile_bodies), dtype=np.int64)

    def read(self, rng: np.random.Generator | None = None) -> list[PadReading]:
        """Measures every pad at the current simulation state.

        Args:
            rng: Noise source for the images, or None for deterministic noise-free images.

        Returns:
            One :class:`PadReading` per pad, in ``pads`` order.
        """
        forces = [
            pad_forces(self.client, self.robot, pad.link, self.tactile_bodies) for pad in self.pads
        ]
        touched = [i for i, f in enumerate(forces) if f]
        gaps = self._gap_maps(touched, forces)
        readings = []
        for i, sensor in enumerate(self._sensors):
            cfg = sensor.cfg
            if i not in gaps:
                h = np.zeros((cfg.height, cfg.width), dtype=np.float32)
                readings.append(PadReading(forces[i], None, h, sensor.untouched(rng)))
                continue
            body, gap = gaps[i]
            h = self._indentation(body, gap, forces[i], cfg)
            readings.append(PadReading(forces[i], gap, h, sensor.shade(h, rng)))
        return readings

    def render(self, rng: np.random.Generator | None = None) -> list[np.ndarray]:
        """Images of every pad, ``(height, width, 3)`` uint8 each, in ``pads`` order."""
        return [r.image for r in self.read(rng)]

    def _gap_maps(
        self, which: list[int], forces: list[dict[int, float]]
    ) -> dict[int, tuple[np.ndarray, np.ndarray]]:
        """Coarse ``(body, gap)`` maps of the pads ``which``, all rays in one batch."""
        if not which:
            return {}
        starts, dirs, within = [], [], []
        for i in which:
            pos, rot = link_pose(self.client, self.robot, self.pads[i].link)
            local_starts, local_dir = self._local[i]
            starts.append(local_starts @ rot.T + pos)
            dirs.append(np.broadcast_to(rot @ local_dir, local_starts.shape))
            push = max(push_depth(f, self._sensors[i].cfg) for f in forces[i].values())
            limit = self.rays.behind + push + self.rays.floor
            within.append(np.full(len(local_starts), limit))
        length = self.rays.behind + self.rays.reach
        body, dist = _cast_rays(
            self.client,
            np.concatenate(starts),
            np.concatenate(dirs),
            length,
            self._tactile,
            self.rays,
            np.concatenate(within),
        )
        rows, cols = self.grid
        out = {}
        for k, i in enumerate(which):
            sl = slice(k * rows * cols, (k + 1) * rows * cols)
            out[i] = (
                body[sl].reshape(rows, cols),
                (dist[sl] - self.rays.behind).reshape(rows, cols),
            )
        return out

    def _indentation(
        self, body: np.ndarray, gap: np.ndarray, forces: dict[int, float], cfg: DigitConfig
    ) -> np.ndarray:
        """Full-resolution indentation from a coarse gap map (see the module docstring, 3)."""
        floor = self.rays.floor
        clearance = np.full(gap.shape, -floor, dtype=np.float32)
        for b, f in forces.items():
            hit = body == b
            clearance[hit] = push_depth(f, cfg) - gap[hit]
        np.maximum(clearance, -floor, out=clearance)
        # Catmull-Rom keeps a constant constant: pixels whose taps all sit at the floor stay
        # there (h = 0), so only the part near touching cells is resampled (a 1 cm sphere at
        # 10 N: about a tenth of the image).
        h = np.zeros((cfg.height, cfg.width), dtype=np.float32)
        active = clearance > -floor
        rows = _reach(active.any(axis=1), cfg.height)
        cols = _reach(active.any(axis=0), cfg.width)
        if rows is None or cols is None:
            return h
        patch = upsample(clearance, (cfg.height, cfg.width), rows, cols)
        np.maximum(patch, 0.0, out=patch)
        h[rows, cols] = patch
        return h


def render_pad(
    client: int,
    robot: int,
    pad: PadSpec,
    tactile_bodies: Collection[int],
    cfg: DigitConfig | None = None,
    rng: np.random.Generator | None = None,
    rays: RayOptions | None = None,
) -> np.ndarray:
    """One pad's tactile image at the current simulation state.

    Convenience for a single call; a loop should keep a :class:`TactilePads` (it caches the
    ray grid and the sensors' reference images, and batches the rays of several pads).

    Args:
        client: PyBullet physics client id.
        robot: The robot's body id.
        pad: Where the gel is on which link.
        tactile_bodies: Body ids the sensor sees.
        cfg: Image config (default RMB's 480 x 640); the pad's gel size replaces its own.
        rng: Noise source, or None for a deterministic image.
        rays: Ray grid and reach.

    Returns:
        ``(height, width, 3)`` uint8 RGB: the reference image (plus noise) when no tactile body
        touches the pad.
    """
    return TactilePads(client, robot, [pad], tactile_bodies, cfg, rays).render(rng)[0]
