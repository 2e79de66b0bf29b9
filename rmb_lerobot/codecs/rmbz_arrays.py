"""Array steps of the ``rmbz`` depth codec: quantisation, hole mask, reference image, packing.

All integer arithmetic, so the decoder reproduces the encoder exactly on any machine.
"""

from __future__ import annotations

import lzma

import numpy as np

from rmb_lerobot.codecs.depth_base import MAX_DEPTH_MM

BLOCK = 16  # reference blocks: exact or smoothed keyframe, chosen per BLOCK x BLOCK pixels
SMOOTH_RADIUS = 2  # 5x5 box average: removes most sensor noise from the reference

_MASK_FILTERS = [{"id": lzma.FILTER_LZMA2, "preset": 6, "lc": 0, "lp": 0, "pb": 0}]


def quantize(mm: np.ndarray, step: int) -> np.ndarray:
    """uint16 mm -> int32 ``round(mm / step)`` (error <= step // 2 mm)."""
    return (mm.astype(np.int32) + step // 2) // step


def dequantize(q: np.ndarray, hole: np.ndarray, step: int) -> np.ndarray:
    """Quantised depth -> uint16 mm, holes -> 0."""
    mm = np.minimum(q.astype(np.int64) * step, MAX_DEPTH_MM)
    mm[hole] = 0
    return mm.astype(np.uint16)


def fill_from_left(q: np.ndarray, hole: np.ndarray) -> np.ndarray:
    """Replace holes by the nearest valid pixel to their left (leading holes stay as they are)."""
    if not hole.any():
        return q
    cols = np.where(hole, 0, np.arange(q.shape[1])[None, :])
    np.maximum.accumulate(cols, axis=1, out=cols)
    return np.take_along_axis(q, cols, axis=1)


def box_smooth(q: np.ndarray, radius: int = SMOOTH_RADIUS) -> np.ndarray:
    """Rounded integer mean over a (2r+1)^2 window with edge padding."""
    n = 2 * radius + 1
    table = np.zeros((q.shape[0] + 2 * radius + 1, q.shape[1] + 2 * radius + 1), dtype=np.int64)
    table[1:, 1:] = np.pad(q, radius, mode="edge")
    table = table.cumsum(0).cumsum(1)
    h, w = q.shape
    total = table[n:, n:] - table[:h, n:] - table[n:, :w] + table[:h, :w]
    return ((total + n * n // 2) // (n * n)).astype(np.int32)


def _block_sums(a: np.ndarray) -> np.ndarray:
    rows = np.add.reduceat(a, np.arange(0, a.shape[0], BLOCK), axis=0)
    return np.add.reduceat(rows, np.arange(0, a.shape[1], BLOCK), axis=1)


def reference_image(base: np.ndarray, target: np.ndarray, target_hole: np.ndarray) -> np.ndarray:
    """The image P-frames are predicted from: ``base`` or its box average, per block.

    A block is smoothed where the smoothed base predicts ``target`` (the next frame) better:
    true for sensor noise (the average removes the base's own noise), false for clean rendered
    depth, where the exact base predicts static pixels without error.
    """
    smooth = box_smooth(base)
    err_exact = np.abs(target - base)
    err_smooth = np.abs(target - smooth)
    err_exact[target_hole] = 0
    err_smooth[target_hole] = 0
    use_smooth = _block_sums(err_smooth) < _block_sums(err_exact)
    mask = np.repeat(np.repeat(use_smooth, BLOCK, axis=0), BLOCK, axis=1)
    return np.where(mask[: base.shape[0], : base.shape[1]], smooth, base)


def fold10(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """0..65535 -> (Y, V) 10-bit planes: V = q >> 10, Y = q & 1023 mirrored where V is odd.

    Mirroring keeps Y continuous when q crosses a multiple of 1024 (like RMB's 8-bit fold).
    """
    hi = q >> 10
    lo = q & 1023
    return np.where(hi & 1, 1023 - lo, lo).astype(np.uint16), hi.astype(np.uint16)


def unfold10(y: np.ndarray, v: np.ndarray) -> np.ndarray:
    v = v.astype(np.int32)
    y = y.astype(np.int32)
    return (v << 10) | np.where(v & 1, 1023 - y, y)


def _varints(values: np.ndarray) -> bytes:
    """LEB128 encoding of non-negative ints < 2^35 (vectorised)."""
    v = values.astype(np.uint64)
    nbytes = 1 + sum((v >= (1 << (7 * k))).astype(np.int64) for k in range(1, 5))
    out = np.zeros(int(nbytes.sum()), dtype=np.uint8)
    start = np.cumsum(nbytes) - nbytes
    for k in range(5):
        sel = nbytes > k
        more = (nbytes[sel] > k + 1).astype(np.uint64) << np.uint64(7)
        out[start[sel] + k] = ((v[sel] >> np.uint64(7 * k)) & np.uint64(0x7F)) | more
    return out.tobytes()


def _read_varints(buf: np.ndarray) -> np.ndarray:
    ends = np.flatnonzero(buf < 0x80)
    if len(buf) and (not len(ends) or ends[-1] != len(buf) - 1):
        raise ValueError("truncated varint")
    starts = np.concatenate([[0], ends[:-1] + 1]).astype(np.int64)
    if np.any(ends - starts >= 5):
        raise ValueError("varint too long")
    values = np.zeros(len(ends), dtype=np.uint64)
    for k in range(5):
        pos = starts + k
        sel = pos <= ends
        values[sel] |= (buf[pos[sel]] & 0x7F).astype(np.uint64) << np.uint64(7 * k)
    return values.astype(np.int64)


def encode_mask(hole: np.ndarray) -> bytes:
    """Hole mask -> LZMA2 of alternating run lengths (valid, hole, ...); b"" if no holes."""
    flat = hole.ravel()
    if not flat.any():
        return b""
    edges = np.flatnonzero(flat[1:] != flat[:-1]) + 1
    runs = np.diff(np.concatenate([[0], edges, [flat.size]]))
    if flat.size and flat[0]:
        runs = np.concatenate([[0], runs])
    return lzma.compress(_varints(runs), format=lzma.FORMAT_RAW, filters=_MASK_FILTERS)


def decode_mask(blob: bytes, shape: tuple[int, int]) -> np.ndarray:
    if not blob:
        return np.zeros(shape, dtype=bool)
    raw = lzma.decompress(blob, format=lzma.FORMAT_RAW, filters=_MASK_FILTERS)
    runs = _read_varints(np.frombuffer(raw, dtype=np.uint8))
    if runs.sum() != shape[0] * shape[1]:
        raise ValueError("hole mask runs do not cover the frame")
    values = np.arange(len(runs)) % 2 == 1
    return np.repeat(values, runs).reshape(shape)
