"""Describe episodes: keys, shapes, dtypes, value ranges, attributes (RMB's PrintRmbData).

Per episode: format, steps, control rate (from ``time``), attributes, and per key its shape,
dtype and minimum/maximum (per dimension too, in the JSON form). Images are only decoded with
``image_stats=True`` (every frame of every video: slow on long episodes). Non-finite values
are counted instead of refused, since finding them is what this tool is for. Over all
episodes, RMB's summary: episode length mean/std/min/max and how many episodes succeed once
(``reward > 0`` at some step) and at the end.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from rmb_lerobot import keys as K
from rmb_lerobot.episode import find_episodes, open_episode
from rmb_lerobot.errors import RmbFormatError

_CHUNK = 8  # frames decoded per read


def _jsonable(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, bytes):
        return value.decode("utf-8", "replace")
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)
    return value


def _finite_range(data: np.ndarray) -> tuple[float | None, float | None, int]:
    """(min, max) of the finite values, and the number of non-finite ones."""
    if data.dtype.kind in "biu":
        if data.size == 0:
            return None, None, 0
        return float(data.min()), float(data.max()), 0
    finite = np.isfinite(data)
    bad = int(data.size - finite.sum())
    if bad == data.size:
        return None, None, bad
    return float(data[finite].min()), float(data[finite].max()), bad


def _per_dim(data: np.ndarray) -> tuple[list, list] | None:
    if data.ndim != 2 or data.shape[0] == 0:
        return None
    masked = np.ma.masked_invalid(data.astype(np.float64))
    low, high = masked.min(axis=0), masked.max(axis=0)
    return (
        [None if v is np.ma.masked else float(v) for v in low],
        [None if v is np.ma.masked else float(v) for v in high],
    )


def _key_info(series, key: str, image_stats: bool) -> dict[str, Any]:
    shape = tuple(int(n) for n in series.shape)
    if K.is_rgb_image_key(key):
        dtype = "uint8"
    elif K.is_depth_image_key(key):
        dtype = "float32"  # as read: metres (videos store millimetres)
    else:
        dtype = str(series.dtype)
    info: dict[str, Any] = {"shape": list(shape), "dtype": dtype}
    if K.is_image_key(key) and not image_stats:
        return info
    low = high = None
    bad = 0
    for start in range(0, max(shape[0], 1), _CHUNK) if K.is_image_key(key) else [None]:
        data = np.asarray(series[:] if start is None else series[start : start + _CHUNK])
        lo, hi, nb = _finite_range(data)
        bad += nb
        if lo is not None:
            low = lo if low is None else min(low, lo)
            high = hi if high is None else max(high, hi)
        if start is None and (per_dim := _per_dim(data)) is not None:
            info["min_per_dim"], info["max_per_dim"] = per_dim
    info.update(min=low, max=high, non_finite=bad)
    return info


def episode_info(path: str | Path, *, image_stats: bool = False) -> dict[str, Any]:
    """Everything :func:`format_info` prints about one episode, as JSON-ready data."""
    with open_episode(path, allow_non_finite=True, allow_missing_depth=True) as episode:
        info: dict[str, Any] = {
            "path": str(path),
            "format": episode.format.value,
            "steps": len(episode),
            "attrs": {k: _jsonable(v) for k, v in episode.attrs.items()},
        }
        try:
            info["fps"] = episode.fps if K.TIME in episode else None
        except RmbFormatError as exc:
            info["fps"] = None
            info["fps_error"] = str(exc)
        keys = {}
        bar = tqdm(
            episode.keys(), desc=Path(path).name, unit="key", leave=False, disable=not image_stats
        )
        for key in bar:  # slow only when decoding images
            keys[key] = _key_info(episode[key], key, image_stats)
        info["keys"] = keys
        if K.REWARD in episode:
            reward = np.asarray(episode[K.REWARD][:], dtype=np.float64).reshape(len(episode), -1)
            info["success_once"] = bool(np.any(reward > 0))
            info["success_last"] = bool(len(reward) and np.any(reward[-1] > 0))
        else:
            info["success_once"] = info["success_last"] = False
    return info


def summary(infos: list[dict[str, Any]], num_failed: int = 0) -> dict[str, Any]:
    """RMB's statistics over episodes: length mean/std/min/max, successes once / at the end."""
    lengths = np.array([info["steps"] for info in infos], dtype=np.int64)
    out: dict[str, Any] = {"episodes": len(infos), "unreadable": num_failed}
    if len(lengths):
        out.update(
            length_mean=float(lengths.mean()),
            length_std=float(lengths.std()),
            length_min=int(lengths.min()),
            length_max=int(lengths.max()),
        )
    out["success_once"] = sum(info["success_once"] for info in infos)
    out["success_last"] = sum(info["success_last"] for info in infos)
    return out


def collect_info(
    sources: Iterable[str | Path], *, image_stats: bool = False, progress: bool = True
) -> tuple[list[dict[str, Any]], list[tuple[Path, str]]]:
    """Info of every episode in ``sources``; unreadable ones as (path, error) pairs."""
    episodes = find_episodes(*sources)
    infos, errors = [], []
    for path in tqdm(
        episodes, desc="info", unit="episode", disable=not progress or len(episodes) < 2
    ):
        try:
            infos.append(episode_info(path, image_stats=image_stats))
        except (RmbFormatError, OSError) as exc:
            errors.append((path, str(exc)))
    return infos, errors


def _num(value: Any) -> str:
    return "-" if value is None else f"{value:.6g}"


def format_info(info: dict[str, Any]) -> str:
    """A human-readable description of one episode."""
    fps = "unknown" if info["fps"] is None else f"{info['fps']:.6g} Hz"
    lines = [f"{info['path']}: {info['format']}, {info['steps']} steps, {fps}"]
    if "fps_error" in info:
        lines.append(f"  control rate: {info['fps_error']}")
    lines.append("  attrs:")
    lines += [f"    {name}: {value!r}" for name, value in info["attrs"].items()]
    lines.append("  keys:")
    width = max((len(k) for k in info["keys"]), default=0)
    for key, k in info["keys"].items():
        shape = str(tuple(k["shape"]))
        line = f"    {key:<{width}}  {shape:<20} {k['dtype']:<8}"
        if "min" in k:
            line += f" min {_num(k['min'])}  max {_num(k['max'])}"
            if k["non_finite"]:
                line += f"  ({k['non_finite']} non-finite)"
        lines.append(line.rstrip())
    return "\n".join(lines)


def format_summary(stats: dict[str, Any]) -> str:
    n = stats["episodes"]
    lines = [
        f"{n} episode(s)" + (f", {stats['unreadable']} unreadable" if stats["unreadable"] else "")
    ]
    if n:
        lines.append(
            f"  length mean {stats['length_mean']:.1f}, std {stats['length_std']:.1f}, "
            f"min {stats['length_min']}, max {stats['length_max']}"
        )
        lines.append(
            f"  success once: {stats['success_once']} / {n}, last: {stats['success_last']} / {n}"
        )
    return "\n".join(lines)
