"""Turn ``reader[index]`` arguments into frame positions, the same way for every reader."""

from __future__ import annotations

import operator

import numpy as np

FrameIndex = int | slice | list[int] | np.ndarray


def resolve_index(index: FrameIndex, length: int) -> tuple[list[int], bool]:
    """Return (non-negative positions, whether the caller asked for a single frame).

    Accepts an int (negative counts from the end), a slice, or a sequence / 1-D integer array
    of ints. Out-of-range positions raise ``IndexError`` like a list would.
    """
    if isinstance(index, slice):
        return list(range(*index.indices(length))), False
    if isinstance(index, (int, np.integer)):
        return [_check(operator.index(index), length)], True
    if isinstance(index, np.ndarray):
        if index.ndim != 1 or not np.issubdtype(index.dtype, np.integer):
            raise TypeError(f"frame index array must be 1-D ints, got {index.dtype} {index.shape}")
        return [_check(int(i), length) for i in index], False
    if isinstance(index, (list, tuple)):
        return [_check(operator.index(i), length) for i in index], False
    raise TypeError(f"frame index must be int, slice or list of ints, got {type(index).__name__}")


def _check(i: int, length: int) -> int:
    if not -length <= i < length:
        raise IndexError(f"frame index {i} out of range for {length} frames")
    return i + length if i < 0 else i
