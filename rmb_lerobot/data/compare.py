"""Compare two episodes key by key against tolerances (RMB's CompareRmbData, with a verdict).

The original prints the mean and maximum absolute error of every key that differs. Here each
key gets the measure that means something for it, and a tolerance:

* RGB images: PSNR in dB of the worst frame (lossy H.264 in the compact variant costs some:
  the synthetic test episodes come back at about 40 dB), at least ``min_psnr``;
* depth images: maximum absolute difference in millimetres, at most ``depth_mm`` (the compact
  variant stores whole millimetres; "no data" pixels, i.e. NaN, inf, <= 0 or beyond what
  uint16 millimetres hold, compare equal to each other whatever their value);
* everything else: maximum absolute difference, at most ``atol`` (NaN equals NaN).

Keys in only one episode, different lengths, shapes or attributes (except ``format``, which
names the variant) are differences too; with different lengths the common first steps are
compared. :attr:`Comparison.ok` is the verdict (the CLI's exit code).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from rmb_lerobot import keys as K
from rmb_lerobot.codecs.depth_base import MAX_DEPTH_MM
from rmb_lerobot.episode import open_episode
from rmb_lerobot.episode.digest import ATTR_VIDEO_SHA256

_CHUNK = 8  # frames per read; two 640x480 two-camera episodes peak at 0.24 GB RSS
# The digests describe the bytes of each episode's own video files (re-encoding changes them).
IGNORED_ATTRS = (K.ATTR_FORMAT, ATTR_VIDEO_SHA256)


@dataclass(frozen=True)
class Tolerances:
    atol: float = 1e-6
    min_psnr: float = 30.0
    depth_mm: float = 1.0


@dataclass
class Row:
    """One line of the comparison: a key (or attribute) and how it differs."""

    key: str
    measure: str  # "max abs", "PSNR dB", "max mm", or a problem ("missing in B", ...)
    value: float | None
    limit: float | None
    ok: bool
    detail: str = ""


@dataclass
class Comparison:
    a: Path
    b: Path
    steps: tuple[int, int]
    rows: list[Row] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return all(row.ok for row in self.rows)

    @property
    def failures(self) -> list[Row]:
        return [row for row in self.rows if not row.ok]

    def to_json(self) -> dict[str, Any]:
        def num(v):
            return None if v is None else (v if math.isfinite(v) else str(v))

        return {
            "a": str(self.a),
            "b": str(self.b),
            "steps": list(self.steps),
            "ok": self.ok,
            "rows": [
                {**row.__dict__, "value": num(row.value), "limit": num(row.limit)}
                for row in self.rows
            ],
        }


def _psnr(mse: float) -> float:
    return math.inf if mse == 0 else 10 * math.log10(255.0**2 / mse)


def _abs_diff(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    if a.dtype.kind in "biu" and b.dtype.kind in "biu":
        return np.abs(a.astype(np.int64) - b.astype(np.int64)).astype(np.float64)
    a = a.astype(np.float64)
    b = b.astype(np.float64)
    with np.errstate(invalid="ignore"):
        diff = np.abs(a - b)
    same = (a == b) | (np.isnan(a) & np.isnan(b))  # equal infinities, NaN against NaN
    diff[same] = 0.0
    diff[~same & ~np.isfinite(diff)] = np.inf  # NaN against a number
    return diff


def _depth_diff_mm(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """|a - b| in mm; 0 where neither has data, inf where only one has."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    has_a, has_b = _has_depth(a), _has_depth(b)
    with np.errstate(invalid="ignore"):
        diff = np.abs(a - b) * 1000.0
    diff[~has_a & ~has_b] = 0.0
    diff[has_a != has_b] = np.inf
    return diff


def _has_depth(depth_m: np.ndarray) -> np.ndarray:
    """Pixels with a depth the compact variant can store (others read back as 0, no data)."""
    with np.errstate(invalid="ignore"):
        mm = depth_m * 1000.0
        return np.isfinite(mm) & (mm >= 0.5) & (mm < MAX_DEPTH_MM + 0.5)


def _chunks(series_a, series_b, steps: int, chunked: bool):
    if not chunked:
        yield np.asarray(series_a[:steps]), np.asarray(series_b[:steps])
        return
    for start in range(0, steps, _CHUNK):
        stop = min(start + _CHUNK, steps)
        yield np.asarray(series_a[start:stop]), np.asarray(series_b[start:stop])


def _compare_key(key: str, sa, sb, steps: int, tol: Tolerances) -> Row:
    if tuple(sa.shape[1:]) != tuple(sb.shape[1:]):
        return Row(key, "shape differs", None, None, False, f"{sa.shape} vs {sb.shape}")
    if K.is_rgb_image_key(key):
        worst, worst_step = math.inf, None
        for i, (a, b) in enumerate(_chunks(sa, sb, steps, True)):
            for j in range(len(a)):
                diff = a[j].astype(np.int32) - b[j].astype(np.int32)
                psnr = _psnr(float(np.mean(diff * diff)))
                if psnr < worst:
                    worst, worst_step = psnr, i * _CHUNK + j
        detail = "" if worst_step is None or math.isinf(worst) else f"worst step {worst_step}"
        return Row(key, "PSNR dB", worst, tol.min_psnr, worst >= tol.min_psnr, detail)
    if K.is_depth_image_key(key):
        worst, worst_step = 0.0, None
        for i, (a, b) in enumerate(_chunks(sa, sb, steps, True)):
            for j in range(len(a)):
                frame_worst = float(_depth_diff_mm(a[j], b[j]).max())
                if frame_worst > worst:
                    worst, worst_step = frame_worst, i * _CHUNK + j
        detail = "" if worst_step is None else f"worst step {worst_step}"
        return Row(key, "max mm", worst, tol.depth_mm, worst <= tol.depth_mm, detail)
    worst = 0.0
    for a, b in _chunks(sa, sb, steps, False):
        if a.size:
            worst = max(worst, float(_abs_diff(a, b).max()))
    return Row(key, "max abs", worst, tol.atol, worst <= tol.atol)


def _show(value: Any) -> str:
    return repr(value.tolist() if isinstance(value, np.ndarray) else value)


def _attr_equal(a: Any, b: Any) -> bool:
    try:
        return bool(np.array_equal(np.asarray(a), np.asarray(b)))
    except (TypeError, ValueError):
        return a == b


def compare_episodes(
    path_a: str | Path,
    path_b: str | Path,
    tolerances: Tolerances = Tolerances(),
    *,
    ignore_attrs: tuple[str, ...] = IGNORED_ATTRS,
    progress: bool = True,
) -> Comparison:
    """Compare every key and attribute of two episodes; see the module documentation."""
    with (
        open_episode(path_a, allow_non_finite=True, allow_missing_depth=True) as a,
        open_episode(path_b, allow_non_finite=True, allow_missing_depth=True) as b,
    ):
        result = Comparison(Path(path_a), Path(path_b), (len(a), len(b)))
        if len(a) != len(b):
            result.rows.append(
                Row(
                    "(steps)",
                    "length differs",
                    None,
                    None,
                    False,
                    f"A has {len(a)} steps, B {len(b)}; comparing the first {min(len(a), len(b))}",
                )
            )
        steps = min(len(a), len(b))
        keys_a, keys_b = set(a.keys()), set(b.keys())
        for key in sorted(keys_a - keys_b):
            result.rows.append(Row(key, "missing in B", None, None, False, f"only in {path_a}"))
        for key in sorted(keys_b - keys_a):
            result.rows.append(Row(key, "missing in A", None, None, False, f"only in {path_b}"))
        common = sorted(keys_a & keys_b)
        for key in tqdm(common, desc="compare", unit="key", disable=not progress):
            result.rows.append(_compare_key(key, a[key], b[key], steps, tolerances))
        attrs_a = {k: v for k, v in a.attrs.items() if k not in ignore_attrs}
        attrs_b = {k: v for k, v in b.attrs.items() if k not in ignore_attrs}
        for name in sorted(attrs_a.keys() | attrs_b.keys()):
            label = f"attr {name}"
            if name not in attrs_b:
                result.rows.append(
                    Row(label, "missing in B", None, None, False, _show(attrs_a[name]))
                )
            elif name not in attrs_a:
                result.rows.append(
                    Row(label, "missing in A", None, None, False, _show(attrs_b[name]))
                )
            elif not _attr_equal(attrs_a[name], attrs_b[name]):
                detail = f"{_show(attrs_a[name])} vs {_show(attrs_b[name])}"
                result.rows.append(Row(label, "differs", None, None, False, detail))
    return result


def format_comparison(result: Comparison, *, only_failures: bool = False) -> str:
    """The comparison as a table, then the verdict."""
    header = ("key", "measure", "value", "tolerance", "status")
    rows = [r for r in result.rows if not (only_failures and r.ok)]

    def num(v: float | None) -> str:
        return "" if v is None else f"{v:.4g}"

    def limit(r: Row) -> str:
        if r.limit is None:
            return ""
        return f">= {num(r.limit)}" if r.measure == "PSNR dB" else f"<= {num(r.limit)}"

    table = [
        (
            r.key,
            r.measure,
            num(r.value),
            limit(r),
            ("ok" if r.ok else "FAIL") + (f"  {r.detail}" if r.detail else ""),
        )
        for r in rows
    ]
    widths = [max(len(x) for x in col) for col in zip(header, *table, strict=False)]
    lines = [f"A: {result.a} ({result.steps[0]} steps)", f"B: {result.b} ({result.steps[1]} steps)"]
    for line in (header, *table):
        cells = [c.ljust(w) for c, w in zip(line[:-1], widths, strict=False)]
        lines.append("  ".join([*cells, line[-1]]).rstrip())
    n_fail = len(result.failures)
    lines.append("within tolerances" if result.ok else f"{n_fail} difference(s) beyond tolerances")
    return "\n".join(lines)
