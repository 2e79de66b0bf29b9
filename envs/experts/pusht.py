"""Scripted expert for the PushT task: push the T-block into its goal pose with the closed
fingertips, one planned push at a time.

The closed gripper's four pads form a ~28 mm square pusher (the only finger geoms that
collide), held pointing down with its lower edge ~1 cm above the table. Each push is planned
from the block's measured pose:

1. candidate pushes: a contact point on one of the T's eight edges (away from its corners), a
   direction within 30 degrees of the edge's inward normal, and a length;
2. each candidate's outcome is predicted with the quasi-static model of a point pusher on a
   block sliding on a table (Lynch et al., ellipsoidal limit surface with the T's
   characteristic length, sticking contact inside the friction cone, sliding on its edge
   otherwise), integrated in 5 mm steps;
3. the candidate with the best progress per unit of time (including the travel to its start)
   towards the target pose wins; the block's pose error counts ``yaw_weight`` metres per
   radian. Pushes that would leave the block where the arm cannot get round it (a corner
   within ``min_block_reach`` of its base, or off the table) are not considered.

The target is first a staging pose with the goal's yaw a few centimetres in front of the goal
(the block turns ~140 degrees, which takes room the arm reaches all round), then the goal.
The pusher travels to the push's start (in the table plane when that keeps clear of the block,
else over it), settles, pushes slowly, backs off a little, and the next push is planned from
the block's new pose: model errors are corrected by this replanning, and a push that did not
move the block (out of the arm's reach) is not tried again from there. The episode ends as
soon as the block is within RMB's tolerance (the env terminates on success).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from rmb_lerobot.envs.experts.base import GripperExpert, Waypoint
from rmb_lerobot.envs.tasks.pusht import (
    BAR_HALF_SIZE,
    GOAL,
    STEM_HALF_SIZE,
    STEM_OFFSET,
    TBLOCK,
    wrap_angle,
    yaw_of,
)

# The T in its body frame: two rectangles (centre, half size), xy.
RECTANGLES = (
    (np.array([0.0, 0.0]), np.array(BAR_HALF_SIZE[:2])),
    (np.array([0.0, STEM_OFFSET]), np.array(STEM_HALF_SIZE[:2])),
)
_BX, _BY = BAR_HALF_SIZE[:2]
_SX, _SY = STEM_HALF_SIZE[:2]
_STEM_TOP = STEM_OFFSET + _SY
# Centre of mass in the body frame (both boxes of one density).
_AREAS = (4 * _BX * _BY, 4 * _SX * _SY)
COM = np.array([0.0, _AREAS[1] * STEM_OFFSET / sum(_AREAS)])
CORNERS = np.array(
    [(-_BX, -_BY), (_BX, -_BY), (_BX, _BY), (_SX, _BY), (_SX, _STEM_TOP), (-_SX, _STEM_TOP),
     (-_SX, _BY), (-_BX, _BY)]
)  # fmt: skip


@dataclass(frozen=True)
class Edge:
    """A straight edge of the T's outline (body frame): from ``a`` to ``b``, its inward normal,
    and whether each end is a concave corner (the square pusher cannot reach close to it)."""

    a: np.ndarray
    b: np.ndarray
    normal: np.ndarray
    concave_a: bool = False
    concave_b: bool = False


def _edge(a, b, normal, concave_a=False, concave_b=False) -> Edge:
    return Edge(
        np.array(a, float), np.array(b, float), np.array(normal, float), concave_a, concave_b
    )


EDGES = (
    _edge((-_BX, -_BY), (_BX, -_BY), (0, 1)),  # under the bar
    _edge((_BX, -_BY), (_BX, _BY), (-1, 0)),  # right end of the bar
    _edge((_BX, _BY), (_SX, _BY), (0, -1), concave_b=True),  # bar top, right of the stem
    _edge((_SX, _BY), (_SX, _STEM_TOP), (-1, 0), concave_a=True),  # right side of the stem
    _edge((_SX, _STEM_TOP), (-_SX, _STEM_TOP), (0, -1)),  # stem tip
    _edge((-_SX, _STEM_TOP), (-_SX, _BY), (1, 0), concave_b=True),  # left side of the stem
    _edge((-_SX, _BY), (-_BX, _BY), (0, -1), concave_a=True),  # bar top, left of the stem
    _edge((-_BX, _BY), (-_BX, -_BY), (1, 0)),  # left end of the bar
)


def _rot2(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return np.cos(theta), np.sin(theta)


def distance_to_block(points: np.ndarray, pos: np.ndarray, yaw: float) -> np.ndarray:
    """Distance (m) in the table plane from world points ``(..., 2)`` to the T at ``pos``
    (its origin, xy) and ``yaw``; 0 inside."""
    c, s = np.cos(yaw), np.sin(yaw)
    rel = np.asarray(points) - pos
    local = np.stack([c * rel[..., 0] + s * rel[..., 1], -s * rel[..., 0] + c * rel[..., 1]], -1)
    dists = []
    for centre, half in RECTANGLES:
        outside = np.maximum(np.abs(local - centre) - half, 0.0)
        dists.append(np.linalg.norm(outside, axis=-1))
    return np.minimum(*dists)


@dataclass
class Candidates:
    """Pushes, one per row: edge contact point (body frame), edge index, direction (world)."""

    contact: np.ndarray  # (n, 2) body frame
    normal: np.ndarray  # (n, 2) body frame inward normal
    tangent_range: np.ndarray  # (n, 2) allowed range of the contact along the edge
    tangent: np.ndarray  # (n, 2) body frame unit tangent
    edge_origin: np.ndarray  # (n, 2) body frame edge start
    direction: np.ndarray  # (n, 2) world push direction


def candidate_pushes(
    yaw: float,
    spacing: float,
    angles: tuple[float, ...],
    convex_margin: float,
    concave_margin: float,
) -> Candidates:
    """Contact points every ``spacing`` along each edge (``*_margin`` from its corners) and push
    directions at ``angles`` (rad) from each edge's inward normal, for the block at ``yaw``."""
    rows = []
    for edge in EDGES:
        length = float(np.linalg.norm(edge.b - edge.a))
        tangent = (edge.b - edge.a) / length
        lo = concave_margin if edge.concave_a else convex_margin
        hi = length - (concave_margin if edge.concave_b else convex_margin)
        if hi < lo:
            continue
        count = max(1, int(np.floor((hi - lo) / spacing)) + 1)
        for t in np.linspace(lo, hi, count) if count > 1 else [(lo + hi) / 2]:
            for angle in angles:
                rows.append((edge.a + t * tangent, edge.normal, (lo, hi), tangent, edge.a, angle))
    contact = np.array([r[0] for r in rows])
    normal = np.array([r[1] for r in rows])
    c, s = np.cos(yaw), np.sin(yaw)
    normal_world = np.stack(
        [c * normal[:, 0] - s * normal[:, 1], s * normal[:, 0] + c * normal[:, 1]], 1
    )
    angle = np.array([r[5] for r in rows])
    ca, sa = np.cos(angle), np.sin(angle)
    direction = np.stack(
        [
            ca * normal_world[:, 0] - sa * normal_world[:, 1],
            sa * normal_world[:, 0] + ca * normal_world[:, 1],
        ],
        1,
    )
    return Candidates(
        contact=contact,
        normal=normal,
        tangent_range=np.array([r[2] for r in rows]),
        tangent=np.array([r[3] for r in rows]),
        edge_origin=np.array([r[4] for r in rows]),
        direction=direction,
    )


def predict_pushes(
    pos: np.ndarray,
    yaw: float,
    cand: Candidates,
    steps: int,
    step_length: float,
    char_length: float,
    friction: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The block's pose after each of ``steps`` pusher advances of ``step_length`` for every
    candidate (quasi-static point pushing, see the module docstring).

    Returns origin positions ``(steps, n, 2)``, yaws ``(steps, n)`` and validity ``(steps, n)``
    (false once the contact has slid off its edge's allowed range).
    """
    n = len(cand.contact)
    c2 = char_length**2
    theta = np.full(n, yaw)
    ct, st = _rot2(theta)
    com = pos + np.stack([ct * COM[0] - st * COM[1], st * COM[0] + ct * COM[1]], 1)
    contact_world = pos + np.stack(
        [
            ct * cand.contact[:, 0] - st * cand.contact[:, 1],
            st * cand.contact[:, 0] + ct * cand.contact[:, 1],
        ],
        1,
    )
    pusher = contact_world.copy()
    u = cand.direction
    valid = np.ones(n, bool)
    out_pos, out_yaw, out_valid = [], [], []
    tan_mu = friction
    for _ in range(steps):
        ct, st = _rot2(theta)
        origin = com - np.stack([ct * COM[0] - st * COM[1], st * COM[0] + ct * COM[1]], 1)
        # The pusher point on the edge (body frame), its tangential coordinate.
        rel = pusher - origin
        local = np.stack([ct * rel[:, 0] + st * rel[:, 1], -st * rel[:, 0] + ct * rel[:, 1]], 1)
        t = np.einsum("ij,ij->i", local - cand.edge_origin, cand.tangent)
        valid &= (t >= cand.tangent_range[:, 0] - 1e-9) & (t <= cand.tangent_range[:, 1] + 1e-9)
        on_edge = cand.edge_origin + t[:, None] * cand.tangent
        point = origin + np.stack(
            [ct * on_edge[:, 0] - st * on_edge[:, 1], st * on_edge[:, 0] + ct * on_edge[:, 1]], 1
        )
        r = point - com
        nrm = np.stack(
            [
                ct * cand.normal[:, 0] - st * cand.normal[:, 1],
                st * cand.normal[:, 0] + ct * cand.normal[:, 1],
            ],
            1,
        )
        rx, ry = r[:, 0], r[:, 1]
        den = c2 + rx**2 + ry**2
        vx = ((c2 + rx**2) * u[:, 0] + rx * ry * u[:, 1]) / den
        vy = (rx * ry * u[:, 0] + (c2 + ry**2) * u[:, 1]) / den
        # Sticking needs the contact force (along the COM velocity) inside the friction cone.
        f_cross = nrm[:, 0] * vy - nrm[:, 1] * vx
        f_dot = nrm[:, 0] * vx + nrm[:, 1] * vy
        slide = np.abs(f_cross) > tan_mu * f_dot
        if np.any(slide):
            sign = np.sign(f_cross[slide])
            phi = np.arctan(tan_mu) * sign
            ns = nrm[slide]
            fx = np.cos(phi) * ns[:, 0] - np.sin(phi) * ns[:, 1]
            fy = np.sin(phi) * ns[:, 0] + np.cos(phi) * ns[:, 1]
            rs = r[slide]
            r_cross_f = rs[:, 0] * fy - rs[:, 1] * fx
            r_cross_n = rs[:, 0] * ns[:, 1] - rs[:, 1] * ns[:, 0]
            u_n = np.einsum("ij,ij->i", u[slide], ns)
            k = u_n / (fx * ns[:, 0] + fy * ns[:, 1] + r_cross_f * r_cross_n / c2)
            vx[slide], vy[slide] = k * fx, k * fy
        omega = (rx * vy - ry * vx) / c2
        if np.any(slide):
            omega[slide] = k * r_cross_f / c2
        com = com + step_length * np.stack([vx, vy], 1)
        theta = theta + step_length * omega
        pusher = pusher + step_length * u
        ct, st = _rot2(theta)
        out_pos.append(com - np.stack([ct * COM[0] - st * COM[1], st * COM[0] + ct * COM[1]], 1))
        out_yaw.append(theta.copy())
        out_valid.append(valid.copy())
    return np.array(out_pos), np.array(out_yaw), np.array(out_valid)


@dataclass
class Move:
    """One straight move of the pusher: target (world), speed (m/s), arrival tolerance (m),
    time limit (s; None: the expert's default) and whether it pushes the block."""

    target: np.ndarray
    speed: float
    tol: float
    rot: Rotation
    pushing: bool = False
    timeout: float | None = None
    at_rest: bool = False  # also wait until the hand is still


@dataclass(frozen=True)
class Push:
    """A planned push: the pusher centre's start (before contact) and end, world xy."""

    start: np.ndarray
    end: np.ndarray
    predicted_cost: float

    @property
    def direction(self) -> np.ndarray:
        delta = self.end - self.start
        return delta / np.linalg.norm(delta)


class PushTExpert(GripperExpert):
    """Tool point: the gripper's pinch point (the centre of the closed pads' square)."""

    push_height = 0.016  # pinch point above the table while pushing (pads' bottom ~1.3 cm)
    travel_height = 0.075  # pinch point above the table when passing over the block
    pusher_half = 0.014  # half size of the closed pads' square (measured, both axes)
    pusher_radius = 0.02  # a disc around the square, for clearance checks
    clearance = 0.01  # kept between the pusher disc and the block when not pushing
    approach = 0.015  # the push starts this far before contact
    retreat = 0.01  # backing off after a push
    char_length = 0.08  # of the T's limit surface (uniform pressure: 0.067 m; corners: 0.098)
    friction = 0.8  # pad-block (MuJoCo takes the larger: the block's 1.0; conservative)
    yaw_weight = 0.3  # m per rad in the pose error (5 degrees weigh as 2.6 cm)
    spacing = 0.01
    angles = tuple(np.deg2rad([-30.0, 0.0, 30.0]))
    convex_margin = 0.006
    concave_margin = 0.02
    step_length = 0.005
    lengths = (0.01, 0.02, 0.03, 0.05, 0.08)
    travel_speed = 0.2  # m/s
    descend_speed = 0.1  # m/s
    push_speed = 0.08  # m/s
    max_correction = 0.02  # m: the integral term's cap (the arm pushes no harder when blocked)
    climb_limit = 0.008  # m: a pusher rising this much over the push height aborts the push
    overhead_time = 0.4  # s per push (accelerating, settling)
    min_reach, max_reach = 0.19, 0.55  # pusher distance from the arm's base in the plane (m)
    block_bounds = (0.25, 0.38)  # block origin within +- these of the table centre (m)
    min_block_reach = 0.17  # every corner of the block stays this far from the arm's base
    # The block is first turned to the goal's yaw at a staging pose this far from the goal,
    # where the pusher reaches all round it, then pushed into the goal.
    stage_offset = (0.08, -0.04)
    stage_tolerance = (0.04, np.deg2rad(12.0))
    no_effect = (0.002, np.deg2rad(1.0))  # a push that moved the block less did not touch it
    waypoint_timeout = 2.0  # s: a waypoint not reached by then (pushing against friction) ends

    def __init__(self, env: Any, **kwargs: Any) -> None:
        kwargs.setdefault("max_speed", self.travel_speed)
        kwargs.setdefault("max_correction", self.max_correction)
        super().__init__(env, **kwargs)

    def on_reset(self) -> None:
        super().on_reset()
        _, self._rot = self.eef_world()
        self._hand_rot = self._rot
        self._queue: list[Move] = []
        self._steps_on_target = 0
        self._closing = True
        self._base = self.scene.body_pose(self.arm.root_frame)[0][:2]
        self._table = np.array(self.env.task.workspace.table.top_centre[:2])
        self._stage_offset = np.array(self.stage_offset)
        self.staging = True
        self.pushes = 0
        self._last_push: Push | None = None
        self._last_pose = self.block_pose()
        self._blocked: list[np.ndarray] = []  # starts of pushes that had no effect

    # ------------------------------------------------------------------ world
    def block_pose(self) -> tuple[np.ndarray, float]:
        pos, rot = self.scene.body_pose(TBLOCK)
        return pos[:2], yaw_of(rot)

    def goal_pose(self) -> tuple[np.ndarray, float]:
        pos, rot = self.scene.body_pose(GOAL)
        return pos[:2], yaw_of(rot)

    def target_pose(self) -> tuple[np.ndarray, float]:
        """Where the pushes aim now: the staging pose (the goal's yaw, in front of the goal)
        while turning the block, then the goal."""
        goal, goal_yaw = self.goal_pose()
        if self.staging:
            return goal + self._stage_offset, goal_yaw
        return goal, goal_yaw

    def pose_cost(self, pos: np.ndarray, yaw: np.ndarray) -> np.ndarray:
        target, target_yaw = self.target_pose()
        dyaw = np.arctan2(np.sin(yaw - target_yaw), np.cos(yaw - target_yaw))
        return np.sqrt(np.sum((pos - target) ** 2, axis=-1) + (self.yaw_weight * dyaw) ** 2)

    def _update_stage(self) -> None:
        """Leave the staging pose for the goal once the block is near it."""
        if not self.staging:
            return
        pos, yaw = self.block_pose()
        target, target_yaw = self.target_pose()
        near = np.linalg.norm(pos - target) < self.stage_tolerance[0]
        turned = abs(wrap_angle(yaw - target_yaw)) < self.stage_tolerance[1]
        if near and turned:
            self.staging = False

    # ------------------------------------------------------------------ planning
    def _reachable(self, xy: np.ndarray) -> np.ndarray:
        dist = np.linalg.norm(xy - self._base, axis=-1)
        return (dist >= self.min_reach) & (dist <= self.max_reach)

    def _clear_of_base(self, pos: np.ndarray, yaw: np.ndarray) -> np.ndarray:
        """Whether every corner of the block at each pose keeps ``min_block_reach`` from the
        arm's base (the pusher must get round it)."""
        c, s = np.cos(yaw)[:, None], np.sin(yaw)[:, None]
        x = pos[:, :1] + c * CORNERS[:, 0] - s * CORNERS[:, 1] - self._base[0]
        y = pos[:, 1:] + s * CORNERS[:, 0] + c * CORNERS[:, 1] - self._base[1]
        return np.hypot(x, y).min(axis=1) >= self.min_block_reach

    def plan(self, fallback: bool = False) -> Push | None:
        """The best push from the block's current pose (None: no push improves it; with
        ``fallback`` the least harmful one)."""
        pos, yaw = self.block_pose()
        cand = candidate_pushes(
            yaw, self.spacing, self.angles, self.convex_margin, self.concave_margin
        )
        # Pusher centre at contact: the square's corner (or face) touching the edge point.
        c, s = np.cos(yaw), np.sin(yaw)
        contact_world = pos + cand.contact @ np.array([[c, s], [-s, c]])
        normal_world = cand.normal @ np.array([[c, s], [-s, c]])
        support = self.pusher_half * np.where(normal_world >= 0, 1.0, -1.0)
        touch = contact_world - support
        u = cand.direction
        # Start before contact, out of the block (measured along the push direction).
        start = touch - (self.approach + self.pusher_radius - self.pusher_half) * u
        ok = distance_to_block(start, pos, yaw) >= self.pusher_radius + self.clearance
        ok &= self._reachable(start)
        for blocked in self._blocked:
            ok &= np.linalg.norm(start - blocked, axis=-1) > 0.015
        steps = round(max(self.lengths) / self.step_length)
        p_pos, p_yaw, p_valid = predict_pushes(
            pos, yaw, cand, steps, self.step_length, self.char_length, self.friction
        )
        now = float(self.pose_cost(pos, np.array(yaw)))
        tcp = self.measured_tool()[:2]
        travel = np.linalg.norm(start - tcp, axis=-1)
        lifted = ~self._in_plane_path(tcp, start, pos, yaw)
        travel_time = travel / self.travel_speed + lifted * (
            2 * (self.travel_height - self.push_height) / self.travel_speed + 0.3
        )
        if self.measured_tool()[2] > self.table_z() + self.push_height + 0.02:
            travel_time = travel_time + (self.travel_height - self.push_height) / self.travel_speed
        half_x, half_y = self.block_bounds
        best, best_score = None, -np.inf if fallback else 0.0
        for length in self.lengths:
            k = round(length / self.step_length) - 1
            end = touch + length * u
            new_pos = p_pos[k]
            rel = np.abs(new_pos - self._table)
            inside = (rel[:, 0] < half_x) & (rel[:, 1] < half_y)
            inside &= self._clear_of_base(new_pos, p_yaw[k])
            cost = self.pose_cost(new_pos, p_yaw[k])
            valid = ok & p_valid[k] & inside & self._reachable(end)
            gain = now - cost
            push_time = (self.approach + length) / self.push_speed
            score = np.where(valid, gain / (travel_time + push_time + self.overhead_time), -np.inf)
            i = int(np.argmax(score))
            if np.isfinite(score[i]) and score[i] > best_score:
                best_score = float(score[i])
                best = Push(start=start[i], end=end[i], predicted_cost=float(cost[i]))
        return best

    def _in_plane_path(
        self, a: np.ndarray, b: np.ndarray, pos: np.ndarray, yaw: float
    ) -> np.ndarray:
        """Whether the straight moves from ``a`` to each row of ``b`` keep clear of the block."""
        if self.measured_tool()[2] > self.table_z() + self.push_height + 0.02:
            return np.zeros(len(b), bool)
        fractions = np.linspace(0.0, 1.0, 9)[:, None, None]
        points = a + fractions * (b - a)
        dist = distance_to_block(points, pos, yaw).min(axis=0)
        return dist >= self.pusher_radius + self.clearance

    def _queue_push(self, push: Push) -> None:
        z_push = self.table_z() + self.push_height
        z_high = self.table_z() + self.travel_height
        tcp = self.measured_tool()
        pos, yaw = self.block_pose()
        travel = self.travel_speed
        rot = self._rot
        if not self._in_plane_path(tcp[:2], push.start[None], pos, yaw)[0]:
            self._queue.append(Move(np.array([*tcp[:2], z_high]), travel, 0.01, self._hand_rot))
            self._queue.append(Move(np.array([*push.start, z_high]), travel, 0.005, rot))
        self._queue.append(
            Move(np.array([*push.start, z_push]), self.descend_speed, 0.004, rot, at_rest=True)
        )
        length = float(np.linalg.norm(push.end - push.start))
        self._queue.append(
            Move(np.array([*push.end, z_push]), self.push_speed, 0.003, rot, pushing=True,
                 timeout=length / self.push_speed + 0.5)
        )  # fmt: skip
        back = push.end + self.retreat * (push.start - push.end) / length
        self._queue.append(Move(np.array([*back, z_push]), travel, 0.004, rot))
        self._hand_rot = rot
        self.pushes += 1
        self._last_push = push
        self._last_pose = self.block_pose()

    def _note_effect(self) -> None:
        """Remember the last push's start if it did not move the block (it cannot be done from
        here: the arm could not reach it, or it missed), so the next plan avoids it."""
        if self._last_push is None:
            return
        (pos0, yaw0), (pos1, yaw1) = self._last_pose, self.block_pose()
        moved = np.linalg.norm(pos1 - pos0) >= self.no_effect[0]
        turned = abs(wrap_angle(yaw1 - yaw0)) >= self.no_effect[1]
        if moved or turned:
            self._blocked.clear()
        else:
            self._blocked.append(self._last_push.start)

    # ------------------------------------------------------------------ policy
    def waypoint(self) -> Waypoint:
        self._track_tool_speed()
        if self._closing:
            if self._gripper_settled():
                self._closing = False
            else:
                return Waypoint(self._ref_pos.copy(), self._rot, self.closed_gripper)
        if self._queue:
            move = self._queue[0]
            self._steps_on_target += 1
            done = (self._arrived if move.at_rest else self.reached)(move.target, move.tol)
            done |= self._steps_on_target * self.dt > (move.timeout or self.waypoint_timeout)
            climbing = self.measured_tool()[2] > move.target[2] + self.climb_limit
            if done or (move.pushing and climbing):
                self._queue.pop(0)
                self._steps_on_target = 0
                if move.pushing and climbing and self._queue:  # back off upwards
                    self._queue[0].target[2] = self.table_z() + self.travel_height
        if not self._queue:
            self._note_effect()
            self._update_stage()
            push = self.plan()
            if push is None and self.staging:
                self.staging = False
                push = self.plan()
            if push is None:
                self._blocked.clear()
                push = self.plan(fallback=True)
            if push is None:  # nothing helps from here: hold still
                self.max_step = self.travel_speed * self.dt
                return Waypoint(self._ref_pos.copy(), self._hand_rot, self.closed_gripper)
            self._queue_push(push)
        move = self._queue[0]
        self.max_step = move.speed * self.dt
        return Waypoint(move.target, move.rot, self.closed_gripper)
