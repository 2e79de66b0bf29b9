"""The one place RMB's float64 values become the dataset's float32: checked, never silent.

A float64 beyond float32's range (about 3.4e38) would become inf in the cast, and NaN/inf would
go into the parquet and poison LeRobot's statistics and every normalised batch; both stop the
conversion here naming the file, key, step and value. ``allow_non_finite`` keeps NaN/inf that
were already in the episode (the user's choice); a finite value is never turned into inf.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rmb_lerobot.errors import RmbFormatError

FLOAT32_MAX = float(np.finfo(np.float32).max)


def _step(row: int, skip: int) -> str:
    if skip == 1:
        return f"step {row}"
    return f"dataset frame {row} (source steps {row * skip}..{row * skip + skip - 1})"


def to_float32(
    values: np.ndarray,
    key: str,
    *,
    path: str | Path | None = None,
    skip: int = 1,
    allow_non_finite: bool = False,
) -> np.ndarray:
    """``values`` ``(T, ...)`` as float32; row ``i`` is dataset frame ``i`` (``skip`` apart)."""
    values = np.asarray(values)
    with np.errstate(over="ignore"):  # overflow is reported below, with its place
        converted = values.astype(np.float32)
    if values.dtype.kind not in "fc":
        return converted  # integers and booleans are always finite
    finite = np.isfinite(values)
    if not allow_non_finite and not finite.all():
        row, *col = np.argwhere(~finite)[0]
        value = float(values[(row, *col)].real)
        count = int((~finite).sum())
        raise RmbFormatError(
            f"{value} at {_step(int(row), skip)}, component {tuple(int(c) for c in col)} "
            f"({count} non-finite values); expected finite numbers (pass --allow-non-finite to "
            "keep NaN/inf)",
            path=path,
            key=key,
        )
    overflow = finite & ~np.isfinite(converted)
    if overflow.any():
        row, *col = np.argwhere(overflow)[0]
        raise RmbFormatError(
            f"{float(values[(row, *col)])!r} at {_step(int(row), skip)}, component "
            f"{tuple(int(c) for c in col)} is beyond float32's range (+-{FLOAT32_MAX:.4g}), the "
            f"dataset's dtype ({int(overflow.sum())} such values); expected values in range",
            path=path,
            key=key,
        )
    return converted
