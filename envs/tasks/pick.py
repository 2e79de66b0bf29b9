"""RMB's MujocoUR5ePick: put the named object (one of nine) into the named basket (one of two).

The layout follows RMB's ``env_ur5e_pick.xml``: nine objects on a 3 x 3 grid with 0.15 m
pitch (y in -0.30, -0.15, 0) and two static baskets behind them at (-0.13, 0.3) and
(0.13, 0.3). The grid sits 5 cm nearer the robot than RMB's (x in -0.2, -0.05, 0.1 instead of
-0.15, 0, 0.15): with a top-down grasp, the far corner of RMB's grid is at the edge of the
UR5e's reach and the forearm sweeps over the near objects on the way there.
RMB's objects are YCB and Google-scanned meshes that are not installed here; this
task builds nine recognisable objects of real-world size and mass from primitives instead,
three of them RMB's YCB items (cracker box, pudding box, potted meat can) and six of the same
kinds as its scanned ones or YCB classics (banana, tape, bottle, apple, cup, mug), every one
graspable by the Robotiq 2F-85 (85 mm opening) from above.

As in RMB, the six worlds shift the *baskets* in x (-0.09 .. 0.06 m) and the random shift
moves every *object* independently (here in x and y only, so nothing starts inside the table).
Shifted layouts are drawn again until no two objects overlap and every object can still be
grasped without the open fingers landing on a neighbour (:func:`layout_is_clear`).

The task is language-conditioned: each episode draws one of the 18 instructions ("Put the
banana in the blue basket.") from the env's generator, or takes
``reset(options={"instruction": ...})``; :attr:`PickTask.description` is the instruction, so it
is the env's ``task_description`` (what LeRobot passes to language-conditioned policies) and
the recorded ``task_desc``. Success: the named object rests (speed < 5 cm/s) inside the named
basket: its origin (the centre of its base) within the basket's inner walls and below its rim.
RMB's own reward counts any object within a generous box around a basket; naming the pair and
requiring the object to be inside makes "right object, wrong basket" and "wrong object, right
basket" failures.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from rmb_lerobot.envs.tasks.base import StartPoses, Task
from rmb_lerobot.envs.workspace import RMB_TABLE, Workspace

if TYPE_CHECKING:
    from rmb_lerobot.envs.scene import SceneState

# The primitive shapes of the objects' geoms (:attr:`Geom.type`).
BOX = "box"
CYLINDER = "cylinder"
CAPSULE = "capsule"
SPHERE = "sphere"

# The open 2F-85 seen from above around its pinch point: fingers reach 72 mm out along the
# closing axis and 15 mm across it (measured on the model); plus a few mm of margin.
FINGER_REACH = 0.078
FINGER_HALF_WIDTH = 0.02
FINGER_DROP = 0.015  # fingertips below the pinch point, plus margin (m)
OBJECT_GAP = 0.01  # minimum gap between two objects' footprints at the start (m)
GRASP_YAWS = np.deg2rad(np.arange(0.0, 180.0, 15.0))  # closing-axis candidates, round objects
MAX_LAYOUT_DRAWS = 200
RING_LIFT = 0.001  # hollow objects' walls above their base (m)


def yaw_quat(yaw: float) -> np.ndarray:
    """Unit quaternion (w, x, y, z) of a rotation by ``yaw`` about the z axis."""
    return np.array([np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2)])


def _mul_quat(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Quaternion product ``a b`` (w, x, y, z): MuJoCo's ``mju_mulQuat``, term by term.

    Bit-identical to it where each component has one non-zero term (as for
    :func:`_lying_quat`'s factors); otherwise the compiled library may fuse multiply-adds.
    """
    return np.array(
        [
            a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
            a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
            a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
            a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
        ]
    )


def _lying_quat(yaw: float) -> np.ndarray:
    """A capsule's axis (its local z) laid horizontally, pointing at ``yaw``."""
    pitch = np.array([np.cos(np.pi / 4), 0.0, np.sin(np.pi / 4), 0.0])  # z -> x
    return _mul_quat(yaw_quat(yaw), pitch)


@dataclass(frozen=True)
class Geom:
    """One primitive of an object, in the object frame (origin: centre of its base).

    ``type`` is :data:`BOX`, :data:`CYLINDER`, :data:`CAPSULE` or :data:`SPHERE`; ``size`` as
    MuJoCo gives it: half sizes (box), radius and half length (cylinder, capsule), radius
    (sphere).
    """

    type: str
    size: tuple[float, ...]
    pos: tuple[float, float, float]
    rgba: tuple[float, float, float, float]
    quat: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)
    collide: bool = True

    def volume(self) -> float:
        s = self.size
        if self.type == BOX:
            return 8.0 * s[0] * s[1] * s[2]
        if self.type == CYLINDER:
            return np.pi * s[0] ** 2 * 2.0 * s[1]
        if self.type == CAPSULE:
            return np.pi * s[0] ** 2 * 2.0 * s[1] + 4.0 / 3.0 * np.pi * s[0] ** 3
        return 4.0 / 3.0 * np.pi * s[0] ** 3


@dataclass(frozen=True)
class PickObject:
    """A graspable object: its primitives, mass, start pose and how the expert grasps it.

    ``footprint`` is the half-size (x, y) of its outline on the table in its own frame;
    ``grasp`` the pinch point in its frame; ``grasp_yaw`` the closing direction in its frame
    (``None``: round, any direction works).
    """

    name: str  # the word in instructions
    geoms: tuple[Geom, ...]
    mass: float  # kg
    slot: tuple[float, float]  # RMB's grid position (x, y)
    yaw: float  # start yaw (rad)
    footprint: tuple[float, float]
    height: float
    grasp: tuple[float, float, float]
    grasp_yaw: float | None

    @property
    def body(self) -> str:
        return "pick_" + self.name.replace(" ", "_")


@dataclass(frozen=True)
class Basket:
    """A static open box; ``inner`` is the half-size (x, y) inside its walls."""

    name: str
    rgba: tuple[float, float, float, float]
    pos: tuple[float, float]
    inner: tuple[float, float]
    height: float  # rim above the table
    wall: float = 0.008
    floor: float = 0.006

    @property
    def body(self) -> str:
        return "pick_" + self.name.replace(" ", "_")


def _ring(radius: float, wall: float, height: float, rgba: tuple, n: int = 12) -> list[Geom]:
    """A thin-walled tube as ``n`` boxes (MuJoCo has no hollow cylinder primitive), standing
    :data:`RING_LIFT` above the object's base so that only a base disk touches the table: dozens
    of box-table contacts would make the scene several times slower to simulate."""
    mid = radius - wall / 2
    half_len = mid * np.tan(np.pi / n) + 0.0005  # overlap slightly: no gaps between boxes
    half_height = (height - RING_LIFT) / 2
    return [
        Geom(
            BOX,
            (wall / 2, half_len, half_height),
            (mid * np.cos(a), mid * np.sin(a), RING_LIFT + half_height),
            rgba,
            quat=tuple(yaw_quat(a)),
        )
        for a in 2 * np.pi * np.arange(n) / n
    ]


def _banana() -> tuple[Geom, ...]:
    """Five capsules along an arc of radius 0.13 m: 18 cm tip to tip, 3.4 cm thick."""
    yellow, brown = (0.93, 0.8, 0.2, 1.0), (0.35, 0.25, 0.1, 1.0)
    r, curve, half_angle, n = 0.017, 0.13, np.deg2rad(34.0), 5
    angles = np.linspace(-half_angle, half_angle, n + 1)
    # Arc bulging towards +y, its chord centred on the origin.
    pts = np.stack([curve * np.sin(angles), curve * np.cos(angles) - curve * np.cos(half_angle)])
    geoms = []
    for a, b in itertools.pairwise(pts.T):
        centre, delta = (a + b) / 2, b - a
        geoms.append(
            Geom(
                CAPSULE,
                (r, np.linalg.norm(delta) / 2),
                (centre[0], centre[1] - 0.008, r),
                yellow,
                quat=tuple(_lying_quat(np.arctan2(delta[1], delta[0]))),
            )
        )
    for end in (pts[:, 0], pts[:, -1]):
        tip = (end[0] * 1.04, end[1] - 0.008, r)
        geoms.append(Geom(SPHERE, (0.006,), tip, brown, collide=False))
    return tuple(geoms)


def _objects() -> tuple[PickObject, ...]:
    """The nine objects with their YCB-like sizes (m) and masses (kg), in RMB's grid order."""
    red, white, green = (0.75, 0.1, 0.08, 1.0), (0.92, 0.92, 0.9, 1.0), (0.2, 0.65, 0.3, 1.0)
    mug_blue, cream = (0.45, 0.6, 0.8, 1.0), (0.9, 0.85, 0.75, 1.0)
    quarter = np.pi / 2
    return (
        PickObject(
            name="banana",
            geoms=_banana(),
            mass=0.12,
            slot=(-0.2, -0.30),
            yaw=quarter,
            footprint=(0.09, 0.03),
            height=0.034,
            grasp=(0.0, 0.014, 0.017),
            grasp_yaw=quarter,
        ),
        PickObject(
            name="cracker box",
            geoms=(
                Geom(BOX, (0.08, 0.03, 0.105), (0.0, 0.0, 0.105), red),
                Geom(
                    BOX,
                    (0.06, 0.0302, 0.03),
                    (0.0, 0.0, 0.12),
                    (0.95, 0.85, 0.2, 1.0),
                    collide=False,
                ),
            ),
            mass=0.41,
            slot=(-0.05, -0.30),
            yaw=quarter,
            footprint=(0.08, 0.03),
            height=0.21,
            grasp=(0.0, 0.0, 0.17),
            grasp_yaw=quarter,
        ),
        PickObject(
            name="tape",
            geoms=(
                *_ring(0.035, 0.013, 0.05, (0.5, 0.2, 0.65, 1.0)),
                # The cardboard core's bottom edge, which the roll stands on.
                Geom(CYLINDER, (0.0225, 0.0015), (0.0, 0.0, 0.0015), (0.75, 0.65, 0.5, 1.0)),
            ),
            mass=0.15,
            slot=(0.1, -0.30),
            yaw=0.0,
            footprint=(0.035, 0.035),
            height=0.05,
            grasp=(0.0, 0.0, 0.028),
            grasp_yaw=None,
        ),
        PickObject(
            name="bottle",
            geoms=(
                Geom(CYLINDER, (0.028, 0.05), (0.0, 0.0, 0.05), white),
                Geom(
                    CYLINDER, (0.0285, 0.02), (0.0, 0.0, 0.05), (0.2, 0.5, 0.3, 1.0), collide=False
                ),
                Geom(CYLINDER, (0.02, 0.01), (0.0, 0.0, 0.11), (0.95, 0.5, 0.1, 1.0)),
            ),
            mass=0.2,
            slot=(-0.2, -0.15),
            yaw=0.0,
            footprint=(0.028, 0.028),
            height=0.12,
            grasp=(0.0, 0.0, 0.08),
            grasp_yaw=None,
        ),
        PickObject(
            name="apple",
            geoms=(
                Geom(SPHERE, (0.036,), (0.0, 0.0, 0.039), red),
                # A flat spot underneath, so the apple does not roll away when touched.
                Geom(CYLINDER, (0.018, 0.0015), (0.0, 0.0, 0.0015), red),
                Geom(
                    CAPSULE, (0.002, 0.006), (0.0, 0.0, 0.079), (0.3, 0.2, 0.1, 1.0), collide=False
                ),
            ),
            mass=0.15,
            slot=(-0.05, -0.15),
            yaw=0.0,
            footprint=(0.036, 0.036),
            height=0.075,
            grasp=(0.0, 0.0, 0.039),
            grasp_yaw=None,
        ),
        PickObject(
            name="cup",
            geoms=(
                *_ring(0.034, 0.005, 0.08, green),
                Geom(CYLINDER, (0.031, 0.003), (0.0, 0.0, 0.003), green),
            ),
            mass=0.12,
            slot=(0.1, -0.15),
            yaw=0.0,
            footprint=(0.034, 0.034),
            height=0.08,
            grasp=(0.0, 0.0, 0.055),
            grasp_yaw=None,
        ),
        PickObject(
            name="pudding box",
            geoms=(
                Geom(BOX, (0.045, 0.0175, 0.055), (0.0, 0.0, 0.055), (0.45, 0.28, 0.15, 1.0)),
                Geom(BOX, (0.03, 0.0177, 0.015), (0.0, 0.0, 0.07), cream, collide=False),
            ),
            mass=0.19,
            slot=(-0.2, 0.0),
            yaw=quarter,
            footprint=(0.045, 0.0175),
            height=0.11,
            grasp=(0.0, 0.0, 0.08),
            grasp_yaw=quarter,
        ),
        PickObject(
            name="mug",
            geoms=(
                *_ring(0.036, 0.006, 0.09, mug_blue),
                Geom(CYLINDER, (0.033, 0.003), (0.0, 0.0, 0.003), mug_blue),
                # The handle, on the +y side.
                Geom(BOX, (0.006, 0.014, 0.004), (0.0, 0.048, 0.072), mug_blue),
                Geom(BOX, (0.006, 0.004, 0.026), (0.0, 0.058, 0.05), mug_blue),
                Geom(BOX, (0.006, 0.014, 0.004), (0.0, 0.048, 0.028), mug_blue),
            ),
            mass=0.3,
            slot=(-0.05, 0.0),
            yaw=0.0,
            footprint=(0.036, 0.064),
            height=0.09,
            grasp=(0.0, 0.0, 0.06),
            grasp_yaw=0.0,
        ),
        PickObject(
            name="meat can",
            geoms=(
                Geom(BOX, (0.05, 0.028, 0.0415), (0.0, 0.0, 0.0415), (0.15, 0.25, 0.6, 1.0)),
                Geom(
                    BOX,
                    (0.0502, 0.0282, 0.005),
                    (0.0, 0.0, 0.078),
                    (0.9, 0.75, 0.15, 1.0),
                    collide=False,
                ),
            ),
            mass=0.37,
            slot=(0.1, 0.0),
            yaw=quarter,
            footprint=(0.05, 0.028),
            height=0.083,
            grasp=(0.0, 0.0, 0.06),
            grasp_yaw=quarter,
        ),
    )


OBJECTS: tuple[PickObject, ...] = _objects()
BASKETS: tuple[Basket, ...] = (
    Basket("blue basket", (0.15, 0.35, 0.8, 1.0), (-0.13, 0.3), (0.092, 0.122), 0.08),
    Basket("black basket", (0.08, 0.08, 0.08, 1.0), (0.13, 0.3), (0.092, 0.122), 0.09),
)
OBJECT_NAMES = tuple(obj.name for obj in OBJECTS)
BASKET_NAMES = tuple(basket.name for basket in BASKETS)


def instruction(object_name: str, basket_name: str) -> str:
    """The language instruction for one (object, basket) pair."""
    return f"Put the {object_name} in the {basket_name}."


INSTRUCTIONS: tuple[str, ...] = tuple(
    instruction(o, b) for o, b in itertools.product(OBJECT_NAMES, BASKET_NAMES)
)
"""The 18 instructions, object-major (as RMB's 18 object-basket combinations)."""


# ---------------------------------------------------------------------- layout geometry
def _corners(centre: np.ndarray, half: Sequence[float], yaw: float) -> np.ndarray:
    c, s = np.cos(yaw), np.sin(yaw)
    local = np.array([[1, 1], [1, -1], [-1, -1], [-1, 1]]) * np.asarray(half)
    return centre + local @ np.array([[c, s], [-s, c]])


def _overlap(a: np.ndarray, b: np.ndarray) -> bool:
    """Separating-axis test for two convex quadrilaterals given by their corners."""
    for poly in (a, b):
        for i in range(4):
            edge = poly[(i + 1) % 4] - poly[i]
            axis = np.array([-edge[1], edge[0]])
            pa, pb = a @ axis, b @ axis
            if pa.max() < pb.min() or pb.max() < pa.min():
                return False
    return True


def footprint(obj: PickObject, xy: np.ndarray, margin: float = 0.0) -> np.ndarray:
    """Corners of the object's outline on the table, grown by ``margin``."""
    return _corners(xy, np.asarray(obj.footprint) + margin, obj.yaw)


def grasp_yaws(obj: PickObject) -> np.ndarray:
    """World yaws of the closing directions the expert may use for ``obj``."""
    if obj.grasp_yaw is None:
        return GRASP_YAWS
    return np.array([obj.yaw + obj.grasp_yaw])


def finger_zone(obj: PickObject, xy: np.ndarray, closing_yaw: float) -> np.ndarray:
    """Where the open fingers come down (seen from above) when grasping ``obj`` at ``xy``."""
    c, s = np.cos(obj.yaw), np.sin(obj.yaw)
    grasp = xy + np.array([[c, -s], [s, c]]) @ np.asarray(obj.grasp[:2])
    return _corners(grasp, (FINGER_REACH, FINGER_HALF_WIDTH), closing_yaw)


def best_grasp_yaw(
    index: int, positions: np.ndarray, objects: Sequence[PickObject] = OBJECTS
) -> float | None:
    """The closing yaw for object ``index`` whose finger zone is clear of every neighbour the
    fingertips come down to (those taller than the pinch point less :data:`FINGER_DROP`),
    preferring the one farthest from them; ``None`` if every candidate hits one."""
    obj = objects[index]
    floor = obj.grasp[2] - FINGER_DROP
    others = [
        (o, p)
        for i, (o, p) in enumerate(zip(objects, positions, strict=True))
        if i != index and o.height > floor
    ]
    best, best_gap = None, -np.inf
    for yaw in grasp_yaws(obj):
        zone = finger_zone(obj, positions[index], yaw)
        if any(_overlap(zone, footprint(o, p)) for o, p in others):
            continue
        centre = zone.mean(axis=0)
        gap = min((float(np.linalg.norm(centre - p)) for _, p in others), default=np.inf)
        if gap > best_gap:
            best, best_gap = float(yaw), gap
    return best


def layout_is_clear(positions: np.ndarray, objects: Sequence[PickObject] = OBJECTS) -> bool:
    """No two objects closer than :data:`OBJECT_GAP`, every object graspable from above."""
    for (i, a), (j, b) in itertools.combinations(enumerate(objects), 2):
        if _overlap(footprint(a, positions[i], OBJECT_GAP / 2), footprint(b, positions[j])):
            return False
    return all(best_grasp_yaw(i, positions, objects) is not None for i in range(len(objects)))


# ---------------------------------------------------------------------- the task
class PickTask(Task):
    """Language-conditioned pick-and-place of one of nine objects into one of two baskets."""

    name = "pick"
    description = "Put the named object in the named basket."  # replaced at every reset
    # RMB's basket shifts (x) of the six worlds.
    world_offsets = np.array([[x, 0.0, 0.0] for x in (-0.09, -0.06, -0.03, 0.0, 0.03, 0.06)])
    max_episode_steps = 500
    # RMB's MujocoUR5ePickEnv start pose (the Toolbox one).
    start_poses: ClassVar[StartPoses] = {
        "ur5e": ((np.pi, -np.pi / 2, -0.55 * np.pi, -0.45 * np.pi, np.pi / 2, np.pi),)
    }
    reset_options = ("instruction",)
    rest_speed = 0.05  # m/s: slower counts as resting

    def __init__(self, workspace: Workspace = RMB_TABLE) -> None:
        super().__init__(workspace)
        self.table_z = workspace.table.top_z
        self.objects = OBJECTS
        self.baskets = BASKETS
        self.target_object = OBJECTS[0]
        self.target_basket = BASKETS[0]
        self.nominal_positions = np.array([obj.slot for obj in OBJECTS])
        self.object_shifts = np.zeros((len(OBJECTS), 2))

    # ------------------------------------------------------------------ episode variant
    def begin_episode(self, rng: np.random.Generator, options: Mapping[str, Any]) -> None:
        """Draw the instruction (always, so the layout under a seed does not depend on whether
        an instruction was given), unless ``options["instruction"]`` names one."""
        index = int(rng.integers(len(INSTRUCTIONS)))
        given = options.get("instruction")
        if given is not None:
            if given not in INSTRUCTIONS:
                raise ValueError(f"unknown instruction {given!r}; one of {INSTRUCTIONS}")
            index = INSTRUCTIONS.index(given)
        self.target_object = self.objects[index // len(self.baskets)]
        self.target_basket = self.baskets[index % len(self.baskets)]
        self.description = INSTRUCTIONS[index]

    def episode_variants(self) -> tuple[dict[str, Any], ...]:
        """The 18 instructions (RMB's dataset holds the same number of demos of each)."""
        return tuple({"instruction": text} for text in INSTRUCTIONS)

    def world_offset(
        self, world_idx: int, rng: np.random.Generator | None = None, random_shift: float = 0.0
    ) -> np.ndarray:
        """The world's basket shift; the random shift moves each object on its own (RMB), drawn
        again until the layout is clear (:func:`layout_is_clear`)."""
        offset = super().world_offset(world_idx, rng, 0.0)
        if random_shift < 0:
            raise ValueError(f"random_shift must be >= 0 metres, got {random_shift!r}")
        self.object_shifts = np.zeros((len(self.objects), 2))
        if random_shift > 0:
            if rng is None:
                raise ValueError("a random shift needs a random generator")
            for _ in range(MAX_LAYOUT_DRAWS):
                shifts = rng.uniform(-random_shift, random_shift, (len(self.objects), 2))
                if layout_is_clear(self.nominal_positions + shifts, self.objects):
                    self.object_shifts = shifts
                    break
            else:
                raise RuntimeError(
                    f"no clear layout in {MAX_LAYOUT_DRAWS} draws with random_shift="
                    f"{random_shift} m; use a smaller shift"
                )
        return offset

    # ------------------------------------------------------------------ success
    def object_in_basket(self, scene: SceneState, obj: PickObject, basket: Basket) -> bool:
        """Whether ``obj`` rests inside ``basket`` (origin within the walls, below the rim)."""
        rel = scene.body_pose(obj.body)[0] - scene.body_pose(basket.body)[0]
        inside = np.all(np.abs(rel[:2]) < basket.inner) and -0.01 < rel[2] < basket.height
        speed = np.linalg.norm(scene.joint_velocity(obj.body)[:3])
        return bool(inside and speed < self.rest_speed)

    def is_success(self, scene: SceneState) -> bool:
        return self.object_in_basket(scene, self.target_object, self.target_basket)
