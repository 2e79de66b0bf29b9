"""Acceptable regions around a demonstration: loading them from YAML, proposing them.

A region is a sphere around the demonstration's tool point at one step (RoboManipAug's
"acceptable region", annotated by the demonstrator): any tool pose inside it may be driven to
the demonstration's pose at ``convergence_idx`` without touching anything, so SART records
motions from there out to the sphere's surface and reverses them. The YAML file::

    regions:
      - time_idx: 30          # sphere centre: the demo's tool pose at this step
        radius: 0.03          # metres
        convergence_idx: 30   # optional (default time_idx): where the reversed motions end
        max_rotation_deg: 5   # optional (default: rotation_scale * radius rad, RMB's 2 rad/m)

:func:`propose_regions` places regions at the gripper's close/open events (the moments where
precision matters); a demonstration without gripper events (Insert holds its peg throughout)
gets one region at the start of its final approach (the last sharp turn of its tool path).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from rmb_lerobot.errors import RmbFormatError

__all__ = [
    "Region",
    "dump_regions",
    "gripper_events",
    "load_regions",
    "propose_regions",
]

_FIELDS = ("time_idx", "radius", "convergence_idx", "max_rotation_deg", "event")
MAX_RADIUS = 0.25  # m; beyond this a "region" is no longer local (and IK may fail)


@dataclass(frozen=True)
class Region:
    """A sphere of ``radius`` metres around the demo's tool pose at ``time_idx``."""

    time_idx: int
    radius: float
    convergence_idx: int | None = None  # None: time_idx
    max_rotation_deg: float | None = None  # None: rotation_scale * radius (radians)
    event: str | None = None  # what a proposal placed it at ("close", "open", "approach")

    @property
    def end_idx(self) -> int:
        """The demo step the reversed motions end at (the convergence point)."""
        return self.time_idx if self.convergence_idx is None else self.convergence_idx

    def max_rotation_rad(self, rotation_scale: float) -> float:
        if self.max_rotation_deg is not None:
            return float(np.deg2rad(self.max_rotation_deg))
        return rotation_scale * self.radius

    def check(self, demo_length: int, *, path: Path | None = None, where: str = "region") -> None:
        """Raise :class:`RmbFormatError` naming the field if this region does not fit the demo."""
        last = demo_length - 2  # the reversed motion must be followed by at least one demo step
        for name in ("time_idx", "convergence_idx"):
            value = getattr(self, name)
            if value is not None and not 0 <= value <= last:
                raise RmbFormatError(
                    f"{name} must be a step of the demo in 0..{last} (the demo has "
                    f"{demo_length} steps and at least one must follow), got {value}",
                    path=path,
                    key=f"{where}.{name}",
                )
        if not 0 < self.radius <= MAX_RADIUS:
            raise RmbFormatError(
                f"radius must be in (0, {MAX_RADIUS}] metres, got {self.radius}",
                path=path,
                key=f"{where}.radius",
            )
        if self.max_rotation_deg is not None and not 0 <= self.max_rotation_deg <= 180:
            raise RmbFormatError(
                f"max_rotation_deg must be in [0, 180], got {self.max_rotation_deg}",
                path=path,
                key=f"{where}.max_rotation_deg",
            )


def _number(value: Any, kind: type, path: Path, key: str) -> Any:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise RmbFormatError(
            f"expected {'an integer' if kind is int else 'a number'}, got {value!r}",
            path=path,
            key=key,
        )
    if kind is int and not float(value).is_integer():
        raise RmbFormatError(f"expected an integer step index, got {value!r}", path=path, key=key)
    return kind(value)


def _region(raw: Any, path: Path, where: str) -> Region:
    if not isinstance(raw, Mapping):
        raise RmbFormatError(
            f"each region must be a mapping with keys {list(_FIELDS[:4])}, got {raw!r}",
            path=path,
            key=where,
        )
    unknown = sorted(set(raw) - set(_FIELDS))
    if unknown:
        raise RmbFormatError(
            f"unknown field(s) {unknown}; a region has {list(_FIELDS)}", path=path, key=where
        )
    for required in ("time_idx", "radius"):
        if required not in raw:
            raise RmbFormatError(
                f"missing required field {required!r}", path=path, key=f"{where}.{required}"
            )
    fields = {
        "time_idx": _number(raw["time_idx"], int, path, f"{where}.time_idx"),
        "radius": _number(raw["radius"], float, path, f"{where}.radius"),
    }
    if raw.get("convergence_idx") is not None:
        fields["convergence_idx"] = _number(
            raw["convergence_idx"], int, path, f"{where}.convergence_idx"
        )
    if raw.get("max_rotation_deg") is not None:
        fields["max_rotation_deg"] = _number(
            raw["max_rotation_deg"], float, path, f"{where}.max_rotation_deg"
        )
    if raw.get("event") is not None:
        fields["event"] = str(raw["event"])
    return Region(**fields)


def load_regions(path: str | Path, demo_length: int | None = None) -> list[Region]:
    """Regions from a YAML file (see the module docs); errors name the file and the field.

    With ``demo_length`` each region is also checked against the demo (indices in range).
    """
    path = Path(path)
    try:
        raw = yaml.safe_load(path.read_text())
    except FileNotFoundError:
        raise RmbFormatError("regions file not found", path=path) from None
    except yaml.YAMLError as exc:
        raise RmbFormatError(f"not valid YAML: {exc}", path=path) from None
    if isinstance(raw, Mapping):
        unknown = sorted(set(raw) - {"regions"})
        if unknown or "regions" not in raw:
            raise RmbFormatError(
                f"expected a top-level 'regions' list, got keys {sorted(raw)}", path=path
            )
        raw = raw["regions"]
    if not isinstance(raw, list) or not raw:
        raise RmbFormatError(
            "expected a non-empty list of regions (under 'regions:'), each with time_idx and "
            f"radius; got {raw!r}",
            path=path,
            key="regions",
        )
    regions = [_region(item, path, f"regions[{i}]") for i, item in enumerate(raw)]
    if demo_length is not None:
        for i, region in enumerate(regions):
            region.check(demo_length, path=path, where=f"regions[{i}]")
    return regions


def dump_regions(regions: Sequence[Region], path: str | Path) -> Path:
    """Write regions as YAML that :func:`load_regions` reads back."""
    path = Path(path)
    items = [{k: v for k, v in asdict(region).items() if v is not None} for region in regions]
    path.write_text(yaml.safe_dump({"regions": items}, sort_keys=False))
    return path


def gripper_events(gripper: np.ndarray, min_change: float = 1e-3) -> list[tuple[int, str]]:
    """Steps at which the gripper command crosses the middle of its range: ``(t, "close")`` when
    it rises past it at step ``t`` (RMB's gripper commands grow as the gripper closes),
    ``(t, "open")`` when it falls. A command that never moves more than ``min_change`` of its
    span (or not at all) has no events."""
    g = np.asarray(gripper, dtype=np.float64)
    g = g.reshape(len(g), -1)[:, 0]
    low, high = float(g.min()), float(g.max())
    if high - low <= max(min_change, 1e-12):
        return []
    above = g > (low + high) / 2
    events = []
    for t in np.flatnonzero(above[1:] != above[:-1]) + 1:
        events.append((int(t), "close" if above[t] else "open"))
    return events


def _turn_angles(positions: np.ndarray, window: int) -> np.ndarray:
    """Per step, the angle (deg) between the tool's motion over the ``window`` steps before and
    after it; 0 where either barely moves (under 2 % of the path length) or near the ends."""
    n = len(positions)
    angles = np.zeros(n)
    path_length = np.linalg.norm(np.diff(positions, axis=0), axis=1).sum()
    min_move = 0.02 * path_length
    for t in range(window, n - window):
        before = positions[t] - positions[t - window]
        after = positions[t + window] - positions[t]
        nb, na = np.linalg.norm(before), np.linalg.norm(after)
        if nb >= min_move and na >= min_move and min_move > 0:
            angles[t] = np.degrees(np.arccos(np.clip(before @ after / (nb * na), -1.0, 1.0)))
    return angles


def _last_turn(positions: np.ndarray, window: int, min_angle_deg: float) -> int | None:
    """The sharpest step of the tool path's last turn of more than ``min_angle_deg``."""
    angles = _turn_angles(positions, window)
    turning = np.flatnonzero(angles >= min_angle_deg)
    if not len(turning):
        return None
    end = start = turning[-1]
    while start > 0 and angles[start - 1] >= min_angle_deg:
        start -= 1
    return int(start + np.argmax(angles[start : end + 1]))


def propose_regions(
    gripper: np.ndarray,
    tool_positions: np.ndarray,
    *,
    radius: float = 0.02,
    lead_steps: int = 1,
    turn_window: int = 5,
    turn_angle_deg: float = 30.0,
) -> list[Region]:
    """Regions at the demo's gripper events (one per close/open), centred ``lead_steps`` before
    the gripper command changes, where the hand is in place and still as it was; without
    gripper events, one region at the last sharp turn of the tool path (the start of the final
    approach), or at the middle of the demo if the path never turns.

    ``gripper``: the demo's ``command_gripper_joint_pos`` (T, g); ``tool_positions``: (T, 3).
    """
    length = len(gripper)
    if length < 3:
        raise RmbFormatError(f"a demo of {length} steps is too short to augment")
    regions = []
    for t, kind in gripper_events(gripper):
        idx = min(max(t - lead_steps, 0), length - 2)
        if regions and regions[-1].time_idx == idx:
            continue
        regions.append(Region(time_idx=idx, radius=radius, event=kind))
    if regions:
        return regions
    positions = np.asarray(tool_positions, dtype=np.float64)
    window = max(1, min(turn_window, (length - 1) // 3))
    turn = _last_turn(positions, window, turn_angle_deg)
    idx = min(turn if turn is not None else length // 2, length - 2)
    return [Region(time_idx=int(idx), radius=radius, event="approach")]
