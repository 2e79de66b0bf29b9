"""Per-robot safety limits of the real arms, as data.

One :class:`SafetyLimits` per arm holds every number :mod:`rmb_lerobot.envs.real.safety`
enforces. The joint names and the gripper command range come from the robot records in
:mod:`rmb_lerobot.envs.robots`; the rest are RMB's real-env numbers
(``envs/real/RealEnvBase.py`` ``overwrite_command_for_safety``,
``envs/real/ur5e/RealUR5eEnvBase.py``, ``envs/real/xarm7/RealXarm7EnvBase.py``):

| rule | UR5e | xArm7 |
| --- | --- | --- |
| joint position bounds | ±2π, elbow ±π | j2 -118..120°, j4 -11..225°, j6 -97..180°, else ±2π |
| velocity limit `v_lim` | 191 °/s | 180 °/s |
| step clamp | ±clip(scale, 0.01, 10) · v_lim · duration, scale 2.0 | same |
| jump refusal | max abs(Δq) > 90° with duration < 0.1 s | same |
| reset duration | clip(max abs(Δq) / (scale · v_lim), 0.1, 10) s | same |
| reset scale | 0.3 | 0.1 |
| gripper command | 0..255 (Robotiq 2F-85) | 0..255 (see below) |

Not RMB's (it has none): the watchdog timeout (0.2 s = 10 periods at 50 Hz), the stale-state
rule (the controller timestamp must advance within 0.1 s and 5 reads) and the optional TCP
workspace box.

Gripper units. The layer clamps the gripper in the units of :meth:`ArmDriver.command_gripper`,
which are the robot record's: 0 (open) .. 255 (closed) for both arms, as RMB's MuJoCo envs and
our recorded datasets spell them. A Robotiq 2F-85 takes exactly that (``SET POS 0..255``, 0 =
open). RMB's real xArm7 env instead sends the xArm SDK's pulse count straight through
(``set_gripper_position(0..840)``, 840 = open, 0 = closed), so its real episodes store 0..840;
our xArm driver maps ``pulse = 840 * (1 - value / 255)`` and back
(:mod:`rmb_lerobot.envs.real.drivers.gripper_units`), after this layer has clamped the value.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from rmb_lerobot.envs.robots import UR5E, UR5E_DUAL, XARM7, Robot

ForwardKinematics = Callable[[np.ndarray], np.ndarray]
"""Arm joint positions (rad) -> TCP position ``(x, y, z)`` in m (a longer vector, e.g. a pose
``(x, y, z, qw, qx, qy, qz)``, is read by its first three entries)."""

# RMB's numbers (RealEnvBase.overwrite_command_for_safety and the two robots' env bases).
STEP_SCALE = 2.0  # RealEnvBase.step: joint_vel_limit_scale=2.0
SCALE_RANGE = (0.01, 10.0)  # np.clip(joint_vel_limit_scale, 0.01, 10.0)
JUMP_THRESHOLD = float(np.deg2rad(90.0))  # arm_joint_pos_error_thre
JUMP_MIN_DURATION = 0.1  # duration_thre (s)
RESET_DURATION_RANGE = (0.1, 10.0)  # duration_min, duration_max (s)
CONTROL_PERIOD = 0.02  # RealEnvBase.dt (s): 50 Hz

# Ours (RMB has none): see the module docstring.
WATCHDOG_TIMEOUT = 0.2  # s: 10 control periods at 50 Hz
STALE_TIMEOUT = 0.1  # s: 5 control periods without a new controller timestamp
MAX_STALE_READS = 5  # consecutive reads with the same timestamp


@dataclass(frozen=True)
class WorkspaceBox:
    """An axis-aligned box the TCP must stay in, in the frame ``fk`` returns positions in.

    Attributes:
        low: Lower corner ``(x, y, z)`` (m).
        high: Upper corner ``(x, y, z)`` (m).
        fk: Forward kinematics of the arm: joint positions to the TCP position.
    """

    low: tuple[float, float, float]
    high: tuple[float, float, float]
    fk: ForwardKinematics = field(compare=False)

    def __post_init__(self) -> None:
        low, high = np.asarray(self.low, float), np.asarray(self.high, float)
        if low.shape != (3,) or high.shape != (3,):
            raise ValueError(f"a workspace box needs 3-vectors, got {self.low}, {self.high}")
        if not (np.all(np.isfinite(low)) and np.all(np.isfinite(high)) and np.all(low < high)):
            raise ValueError(f"workspace box needs finite low < high, got {self.low}, {self.high}")

    def tcp(self, joint_pos: np.ndarray) -> np.ndarray:
        """The TCP position ``(x, y, z)`` of ``joint_pos``.

        Args:
            joint_pos: Arm joint positions (rad).

        Returns:
            The first three entries of ``fk(joint_pos)`` as float64.
        """
        return np.asarray(self.fk(np.asarray(joint_pos, dtype=np.float64)), np.float64)[:3]

    def distance(self, point: np.ndarray) -> float:
        """How far ``point`` lies outside the box (m); 0 inside or on its faces.

        Args:
            point: A position ``(x, y, z)``.

        Returns:
            The Euclidean distance to the box (``nan`` if ``point`` is not finite).
        """
        low, high = np.asarray(self.low), np.asarray(self.high)
        return float(np.linalg.norm(np.maximum(np.maximum(low - point, point - high), 0.0)))


@dataclass(frozen=True)
class SafetyLimits:
    """Every number the safety layer enforces for one arm.

    Attributes:
        robot: The robot record's name (``ur5e``, ``xarm7``).
        joints: Arm joint names, in the order of the joint vector.
        low: Lower joint position bounds (rad), one per joint.
        high: Upper joint position bounds (rad), one per joint.
        v_lim: Joint velocity limit (rad/s), the same for every joint (RMB's).
        gripper: ``(low, high)`` of the gripper command, in the driver's units.
        reset_scale: ``v_lim`` scale of :meth:`SafetyLayer.move_to` (RMB's reset).
        step_scale: ``v_lim`` scale of :meth:`SafetyLayer.step` (RMB's step).
        scale_range: Any scale is clipped into this range first.
        jump_threshold: A step whose max ``|Δq|`` exceeds this (rad) ...
        jump_min_duration: ... with a duration under this (s) is refused.
        reset_duration_range: ``(min, max)`` duration of a reset move (s).
        max_duration: Longest duration a step may ask for (s).
        watchdog_timeout: With the watchdog armed, the arm is stopped when no command arrives
            within this many seconds after the previous command's duration has run out.
        stale_timeout: A reading is stale when the controller timestamp has not advanced for
            this long (s, on the layer's clock) ...
        max_stale_reads: ... or for this many consecutive reads.
        workspace: The TCP box, or ``None`` for no workspace check.
    """

    robot: str
    joints: tuple[str, ...]
    low: tuple[float, ...]
    high: tuple[float, ...]
    v_lim: float
    gripper: tuple[float, float]
    reset_scale: float
    step_scale: float = STEP_SCALE
    scale_range: tuple[float, float] = SCALE_RANGE
    jump_threshold: float = JUMP_THRESHOLD
    jump_min_duration: float = JUMP_MIN_DURATION
    reset_duration_range: tuple[float, float] = RESET_DURATION_RANGE
    max_duration: float = RESET_DURATION_RANGE[1]
    watchdog_timeout: float = WATCHDOG_TIMEOUT
    stale_timeout: float = STALE_TIMEOUT
    max_stale_reads: int = MAX_STALE_READS
    workspace: WorkspaceBox | None = None

    def __post_init__(self) -> None:
        n = len(self.joints)
        if n == 0 or len(self.low) != n or len(self.high) != n:
            raise ValueError(
                f"{self.robot}: {n} joints but {len(self.low)} low and {len(self.high)} high bounds"
            )
        numbers = [
            *self.low,
            *self.high,
            self.v_lim,
            *self.gripper,
            self.reset_scale,
            self.step_scale,
            *self.scale_range,
            self.jump_threshold,
            self.jump_min_duration,
            *self.reset_duration_range,
            self.max_duration,
            self.watchdog_timeout,
            self.stale_timeout,
        ]
        if not all(np.isfinite(numbers)):
            raise ValueError(f"{self.robot}: every limit must be finite")
        for name, lo, hi in zip(self.joints, self.low, self.high, strict=True):
            if not lo < hi:
                raise ValueError(f"{self.robot}: joint {name} bounds {lo} >= {hi}")
        positive = {
            "v_lim": self.v_lim,
            "scale_range low": self.scale_range[0],
            "reset duration min": self.reset_duration_range[0],
            "watchdog_timeout": self.watchdog_timeout,
            "stale_timeout": self.stale_timeout,
            "max_stale_reads": self.max_stale_reads,
        }
        for name, value in positive.items():
            if value <= 0:
                raise ValueError(f"{self.robot}: {name} must be > 0, got {value}")
        pairs = {
            "gripper": self.gripper,
            "scale_range": self.scale_range,
            "reset_duration_range": self.reset_duration_range,
        }
        for name, (lo, hi) in pairs.items():
            if not lo < hi:
                raise ValueError(f"{self.robot}: {name} needs low < high, got ({lo}, {hi})")

    @property
    def num_joints(self) -> int:
        """Number of arm joints (the gripper not counted)."""
        return len(self.joints)

    @property
    def low_array(self) -> np.ndarray:
        """:attr:`low` as a float64 array."""
        return np.asarray(self.low, dtype=np.float64)

    @property
    def high_array(self) -> np.ndarray:
        """:attr:`high` as a float64 array."""
        return np.asarray(self.high, dtype=np.float64)

    def scaled_v_lim(self, scale: float) -> float:
        """RMB's scaled velocity limit ``clip(scale, *scale_range) * v_lim`` (rad/s).

        Args:
            scale: The requested scale (finite).

        Returns:
            The joint velocity limit for that scale.
        """
        return float(np.clip(scale, *self.scale_range)) * self.v_lim


TWO_PI = 2.0 * np.pi

# RealUR5eEnvBase.action_space: every joint +-2 pi, the elbow (index 2) +-pi.
_UR5E_LOW = (-TWO_PI, -TWO_PI, -np.pi, -TWO_PI, -TWO_PI, -TWO_PI)
_UR5E_HIGH = (TWO_PI, TWO_PI, np.pi, TWO_PI, TWO_PI, TWO_PI)
# RealXarm7EnvBase.action_space as meant (RMB's code passes the low bounds, already in rad,
# through np.deg2rad a second time): j2 -118..120, j4 -11..225, j6 -97..180 deg, others +-2 pi.
_XARM7_LOW = tuple(float(np.deg2rad(v)) for v in (-360, -118, -360, -11, -360, -97, -360))
_XARM7_HIGH = tuple(float(np.deg2rad(v)) for v in (360, 120, 360, 225, 360, 180, 360))

# Per robot: (bounds low, bounds high, v_lim rad/s, reset scale).
_REAL_NUMBERS: dict[str, tuple[tuple[float, ...], tuple[float, ...], float, float]] = {
    UR5E.name: (_UR5E_LOW, _UR5E_HIGH, float(np.deg2rad(191.0)), 0.3),
    UR5E_DUAL.name: (_UR5E_LOW, _UR5E_HIGH, float(np.deg2rad(191.0)), 0.3),
    XARM7.name: (_XARM7_LOW, _XARM7_HIGH, float(np.deg2rad(180.0)), 0.1),
}
_RECORDS: dict[str, Robot] = {r.name: r for r in (UR5E, UR5E_DUAL, XARM7)}


def limits_for(
    robot: str,
    *,
    arm: int = 0,
    workspace: WorkspaceBox | None = None,
    gripper: tuple[float, float] | None = None,
    watchdog_timeout: float = WATCHDOG_TIMEOUT,
) -> SafetyLimits:
    """The safety limits of one arm of a real robot.

    Args:
        robot: A robot record's name: ``ur5e``, ``ur5e_dual`` or ``xarm7``.
        arm: Which arm of the record (``ur5e_dual``: 0 left, 1 right).
        workspace: The TCP box of this cell, or ``None`` for none.
        gripper: ``(low, high)`` of the gripper command in the driver's units; ``None``: the
            record's command range (0..255).
        watchdog_timeout: The watchdog timeout (s).

    Returns:
        The limits, joint names from the record, numbers from RMB's real envs.

    Raises:
        KeyError: ``robot`` is not a real robot this package drives.
        IndexError: The record has no arm ``arm``.
    """
    if robot not in _REAL_NUMBERS:
        raise KeyError(f"no real-arm limits for robot {robot!r}; known: {sorted(_REAL_NUMBERS)}")
    record = _RECORDS[robot]
    if not 0 <= arm < len(record.arms):
        raise IndexError(f"robot {robot!r} has {len(record.arms)} arm(s), no arm {arm}")
    record_arm = record.arms[arm]
    low, high, v_lim, reset_scale = _REAL_NUMBERS[robot]
    if len(low) != len(record_arm.joints):
        raise AssertionError(f"{robot}: bounds for {len(low)} joints, record has {record_arm}")
    return SafetyLimits(
        robot=robot,
        joints=record_arm.joints,
        low=low,
        high=high,
        v_lim=v_lim,
        gripper=gripper if gripper is not None else record_arm.gripper.command_range,
        reset_scale=reset_scale,
        watchdog_timeout=watchdog_timeout,
        workspace=workspace,
    )


def ur5e_tcp_fk(tool_offset: float = 0.0) -> ForwardKinematics:
    """UR5e forward kinematics to a TCP ``tool_offset`` m along the flange's z axis.

    Positions are in the base frame of UR's published DH table
    (:data:`rmb_lerobot.kinematics.UR5E`). Check one measured point against it before trusting
    a box: the controller's displayed base frame may be turned about z relative to it.

    Args:
        tool_offset: Flange to TCP along the tool axis (m); a Robotiq 2F-85's fingertips are
            about 0.15 m out.

    Returns:
        A callable joint positions -> TCP position ``(x, y, z)``.
    """
    from rmb_lerobot.kinematics import UR5E as UR5E_DH

    offset = np.array([0.0, 0.0, float(tool_offset), 1.0])

    def fk(joint_pos: np.ndarray) -> np.ndarray:
        return (UR5E_DH.transform(joint_pos) @ offset)[:3]

    return fk
