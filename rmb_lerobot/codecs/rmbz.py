"""``rmbz``: our depth codec. Near-lossless (max error 1 mm) and any frame in two decodes.

Why it beats the RMB depth video (see benchmarks/RESULTS.md):

- Quantisation: ``q = round(mm / 3)`` bounds the error by 1 mm and removes log2(3) bits of
  sensor noise per pixel that a lossless codec must store. ``step_mm=1`` makes it exact.
- Dropouts (0 = no data) are coded once as a run-length mask and filled in ``q`` with a
  prediction, so they cost no residual and never disturb the predictor; they decode to 0.
- "Star" inter prediction: every P-frame is predicted from its keyframe only (never from the
  previous frame), so frame i decodes from exactly two frames (its keyframe and itself) while
  static scenes still cost almost nothing. Per 16x16 block, the prediction is either the keyframe
  (exact for clean, rendered depth) or its 5x5 box average (removes most of the keyframe's
  noise for sensor depth), whichever has the smaller absolute residual.
- Keyframes code the horizontal difference; a new keyframe is made when a P-frame costs more
  than the last keyframe, or at most every 30 frames when it costs more than half of it.
- Residuals are zigzagged to uint16, split into low and high byte planes and coded with raw
  LZMA2 (literal contexts off), which comes within ~2 % of their order-0 entropy.

File: HDF5 with attributes (codec name, format version, step, block size, shape, entropy coder
settings) and datasets ``payload`` (all frames' bytes, appended as frames arrive),
``frame_offset``, ``frame_kind``, ``frame_key``, ``frame_crc32``, written at ``close()``.
"""

from __future__ import annotations

import lzma
import zlib
from collections import OrderedDict
from pathlib import Path

import h5py
import numpy as np

from rmb_lerobot.codecs.depth_base import (
    MAX_DEPTH_MM,
    DepthCodec,
    DepthReader,
    DepthWriter,
    as_depth_mm,
)
from rmb_lerobot.codecs.indexing import FrameIndex, resolve_index
from rmb_lerobot.errors import RmbFormatError

CODEC_ID = "rmbz"
FORMAT_VERSION = 1
INTRA, INTER = 0, 1
BLOCK = 16
SMOOTH_RADIUS = 2
MIN_KEY_GAP = 30  # a stale keyframe is replaced at most this often (intra trials cost time)

# Raw LZMA2 without literal context bits: residuals are close to i.i.d., so context bits only
# dilute statistics. "normal" mode picks literals over short useless matches; the hc3 match
# finder is fast. Keyframes are rarer and get the slower, stronger bt4 match finder.
_LZMA_COMMON = {"id": lzma.FILTER_LZMA2, "lc": 0, "lp": 0, "pb": 0, "mode": lzma.MODE_NORMAL}
_INTER_FILTER = {**_LZMA_COMMON, "mf": lzma.MF_HC3, "depth": 2, "nice_len": 16}
_INTRA_FILTER = {**_LZMA_COMMON, "mf": lzma.MF_BT4, "depth": 8, "nice_len": 64}


def quantize(mm: np.ndarray, step: int) -> np.ndarray:
    """uint16 mm -> int32 ``round(mm / step)`` (error <= step // 2 mm)."""
    return (mm.astype(np.int32) + step // 2) // step


def dequantize(q: np.ndarray, hole: np.ndarray, step: int) -> np.ndarray:
    """Quantised depth -> uint16 mm, holes -> 0."""
    mm = np.minimum(q.astype(np.int64) * step, MAX_DEPTH_MM)
    mm[hole] = 0
    return mm.astype(np.uint16)


def fill_from_left(q: np.ndarray, hole: np.ndarray) -> np.ndarray:
    """Replace holes by the nearest valid pixel to their left (row start: left as is)."""
    if not hole.any():
        return q
    cols = np.where(hole, 0, np.arange(q.shape[1])[None, :])
    np.maximum.accumulate(cols, axis=1, out=cols)
    return np.take_along_axis(q, cols, axis=1)


def box_smooth(q: np.ndarray, radius: int) -> np.ndarray:
    """Rounded integer mean over a (2r+1)^2 window with edge padding; exact, so decodable."""
    n = 2 * radius + 1
    padded = np.pad(q.astype(np.int64), radius + 1, mode="edge")[:-1, :-1]
    padded[0, :] = 0
    padded[:, 0] = 0
    table = padded.cumsum(0).cumsum(1)
    h, w = q.shape
    total = table[n:, n:] - table[:h, n:] - table[n:, :w] + table[:h, :w]
    return ((total + n * n // 2) // (n * n)).astype(np.int32)


def _zigzag(residual: np.ndarray) -> np.ndarray:
    """int32 residual taken modulo 2^16 -> uint16 zigzag (small magnitudes -> small codes)."""
    r16 = residual.astype(np.int16)  # wraps modulo 2^16; decoding wraps back
    return ((r16.astype(np.int32) << 1) ^ (r16.astype(np.int32) >> 15)).astype(np.uint16)


def _unzigzag(z: np.ndarray) -> np.ndarray:
    z = z.astype(np.int32)
    return (z >> 1) ^ -(z & 1)


def _varints(values: np.ndarray) -> bytes:
    """LEB128 encoding of non-negative ints (vectorised)."""
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
    values = np.zeros(len(ends), dtype=np.uint64)
    for k in range(5):
        pos = starts + k
        sel = pos <= ends
        values[sel] |= (buf[pos[sel]] & 0x7F).astype(np.uint64) << np.uint64(7 * k)
    return values.astype(np.int64)


def _mask_runs(hole: np.ndarray) -> bytes:
    """Alternating run lengths (valid, hole, valid, ...) of the raster-order hole mask."""
    flat = hole.ravel()
    if not flat.any():
        return _varints(np.array([flat.size]))
    edges = np.flatnonzero(flat[1:] != flat[:-1]) + 1
    runs = np.diff(np.concatenate([[0], edges, [flat.size]]))
    if flat[0]:
        runs = np.concatenate([[0], runs])
    return _varints(runs)


def _mask_from_runs(buf: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    runs = _read_varints(buf)
    if runs.sum() != shape[0] * shape[1]:
        raise ValueError("mask runs do not cover the frame")
    values = np.arange(len(runs)) % 2 == 1
    return np.repeat(values, runs).reshape(shape)


def _intra_residual(q: np.ndarray) -> np.ndarray:
    d = q.copy()
    d[:, 1:] -= q[:, :-1]
    d[1:, 0] -= q[:-1, 0]
    return d


def _intra_reconstruct(d: np.ndarray) -> np.ndarray:
    d = d.astype(np.int64)
    d[:, 0] = np.cumsum(d[:, 0])
    return (np.cumsum(d, axis=1) & 0xFFFF).astype(np.int32)


def _block_sums(a: np.ndarray) -> np.ndarray:
    h, w = a.shape
    rows = np.add.reduceat(a, np.arange(0, h, BLOCK), axis=0)
    return np.add.reduceat(rows, np.arange(0, w, BLOCK), axis=1)


def _expand_blocks(modes: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    return np.repeat(np.repeat(modes, BLOCK, axis=0), BLOCK, axis=1)[: shape[0], : shape[1]]


class _Reference:
    """A decoded keyframe and its smoothed version: the two inter predictions."""

    def __init__(self, q: np.ndarray):
        self.q = q
        self.smooth = box_smooth(q, SMOOTH_RADIUS)

    def predict(self, modes: np.ndarray) -> np.ndarray:
        return np.where(_expand_blocks(modes, self.q.shape), self.smooth, self.q)


def _pack(z: np.ndarray, extra: bytes, filters: dict, dict_size: int) -> bytes:
    planes = np.concatenate([(z & 0xFF).astype(np.uint8).ravel(), (z >> 8).astype(np.uint8).ravel()])
    data = planes.tobytes() + extra
    return lzma.compress(
        data, format=lzma.FORMAT_RAW, filters=[{**filters, "dict_size": dict_size}]
    )


def _dict_size(height: int, width: int) -> int:
    """Power of two >= the largest raw frame (2 planes + block modes + worst-case mask)."""
    need = 2 * height * width + height * width // BLOCK**2 + 2 * height * width + 64
    return max(1 << 16, 1 << (need - 1).bit_length())


class RmbzWriter(DepthWriter):
    def __init__(self, path: str | Path, width: int, height: int, *, step_mm: int):
        self.path = Path(path)
        self.shape = (int(height), int(width))
        if min(self.shape) <= 0:
            raise RmbFormatError(
                f"bad frame size {width}x{height}; expected positive width and height",
                path=self.path,
            )
        self.step = step_mm
        self._dict_size = _dict_size(*self.shape)
        self._file = h5py.File(self.path, "w")
        attrs = self._file.attrs
        attrs.update(
            codec=CODEC_ID,
            format_version=FORMAT_VERSION,
            step_mm=step_mm,
            height=self.shape[0],
            width=self.shape[1],
            block=BLOCK,
            smooth_radius=SMOOTH_RADIUS,
            entropy="lzma2-raw",
            lzma_dict_size=self._dict_size,
            complete=False,
        )
        self._payload = self._file.create_dataset(
            "payload", shape=(0,), maxshape=(None,), dtype=np.uint8, chunks=(1 << 18,)
        )
        self._offsets = [0]
        self._kinds: list[int] = []
        self._keys: list[int] = []
        self._crcs: list[int] = []
        self._reference: _Reference | None = None
        self._key_index = -1
        self._intra_size = 0
        self._closed = False

    def __len__(self) -> int:
        return len(self._kinds)

    def write(self, frame: np.ndarray) -> None:
        if self._closed:
            raise RmbFormatError("writer is closed; expected no more frames", path=self.path)
        number = len(self)
        mm = as_depth_mm(frame, self.shape, self.path, number)
        hole = mm == 0
        q = quantize(mm, self.step)
        mask = _mask_runs(hole)
        if self._reference is None:
            self._store_intra(q, hole, mask)
            return
        blob, since_key = self._inter(q, hole, mask), number - self._key_index
        stale = len(blob) > self._intra_size or (
            since_key >= MIN_KEY_GAP and 2 * len(blob) > self._intra_size
        )
        if stale:
            filled = fill_from_left(q, hole)
            intra = _pack(
                _zigzag(_intra_residual(filled)), mask, _INTRA_FILTER, self._dict_size
            )
            self._intra_size = len(intra)
            if len(intra) < 2 * len(blob):
                self._append(intra, INTRA, number)
                self._reference, self._key_index = _Reference(filled), number
                return
        self._append(blob, INTER, self._key_index)

    def _store_intra(self, q: np.ndarray, hole: np.ndarray, mask: bytes) -> None:
        filled = fill_from_left(q, hole)
        blob = _pack(_zigzag(_intra_residual(filled)), mask, _INTRA_FILTER, self._dict_size)
        self._intra_size = len(blob)
        self._key_index = len(self)
        self._append(blob, INTRA, self._key_index)
        self._reference = _Reference(filled)

    def _inter(self, q: np.ndarray, hole: np.ndarray, mask: bytes) -> bytes:
        ref = self._reference
        err_key = np.abs(q - ref.q)
        err_smooth = np.abs(q - ref.smooth)
        err_key[hole] = 0
        err_smooth[hole] = 0
        modes = (_block_sums(err_smooth) < _block_sums(err_key)).astype(np.uint8)
        prediction = ref.predict(modes)
        residual = np.where(hole, 0, q - prediction)
        return _pack(_zigzag(residual), modes.tobytes() + mask, _INTER_FILTER, self._dict_size)

    def _append(self, blob: bytes, kind: int, key: int) -> None:
        start = self._offsets[-1]
        self._payload.resize((start + len(blob),))
        self._payload[start:] = np.frombuffer(blob, dtype=np.uint8)
        self._offsets.append(start + len(blob))
        self._kinds.append(kind)
        self._keys.append(key)
        self._crcs.append(zlib.crc32(blob))

    def close(self) -> None:
        """Write the frame index and mark the file complete (idempotent)."""
        if self._closed:
            return
        self._closed = True
        try:
            f = self._file
            f.create_dataset("frame_offset", data=np.asarray(self._offsets, dtype=np.int64))
            f.create_dataset("frame_kind", data=np.asarray(self._kinds, dtype=np.uint8))
            f.create_dataset("frame_key", data=np.asarray(self._keys, dtype=np.int64))
            f.create_dataset("frame_crc32", data=np.asarray(self._crcs, dtype=np.uint32))
            f.attrs.update(n_frames=len(self._kinds), complete=True)
        finally:
            self._file.close()


class RmbzReader(DepthReader):
    """Decodes frame i from its keyframe and itself; recently used keyframes are cached."""

    _CACHED_KEYS = 2

    def __init__(self, path: str | Path):
        self.path = Path(path)
        if not self.path.is_file():
            raise RmbFormatError("depth file not found; expected an rmbz HDF5 file", path=path)
        try:
            self._file = h5py.File(self.path, "r")
        except OSError as exc:
            raise RmbFormatError(
                f"cannot open depth file ({exc}); expected an rmbz HDF5 file", path=path
            ) from exc
        try:
            self._load_index()
        except BaseException:
            self._file.close()
            raise
        self._references: OrderedDict[int, _Reference] = OrderedDict()

    def _fail(self, what: str) -> RmbFormatError:
        return RmbFormatError(f"{what}; expected an rmbz depth file", path=self.path)

    def _load_index(self) -> None:
        attrs = self._file.attrs
        if attrs.get("codec") != CODEC_ID:
            raise self._fail(f"codec attribute is {attrs.get('codec')!r}, not {CODEC_ID!r}")
        if attrs.get("format_version") != FORMAT_VERSION:
            raise self._fail(f"unsupported format_version {attrs.get('format_version')!r}")
        if not attrs.get("complete", False):
            raise self._fail("file is incomplete (its writer was never closed)")
        try:
            self.step = int(attrs["step_mm"])
            self._shape = (int(attrs["height"]), int(attrs["width"]))
            if int(attrs["block"]) != BLOCK or int(attrs["smooth_radius"]) != SMOOTH_RADIUS:
                raise self._fail("unsupported block size or smoothing radius")
            self._dict_size = int(attrs["lzma_dict_size"])
            self._payload = self._file["payload"]
            self._offsets = self._file["frame_offset"][()]
            self._kinds = self._file["frame_kind"][()]
            self._keys = self._file["frame_key"][()]
            self._crcs = self._file["frame_crc32"][()]
        except (KeyError, OSError, ValueError) as exc:
            raise self._fail(f"missing or unreadable metadata ({exc})") from exc
        n = int(attrs.get("n_frames", -1))
        consistent = (
            len(self._offsets) == n + 1
            and len(self._kinds) == len(self._keys) == len(self._crcs) == n
            and self._offsets[-1] == self._payload.shape[0]
            and np.all(np.diff(self._offsets) >= 0)
            and np.all((self._keys >= 0) & (self._keys < max(n, 1)))
            and np.all(self._kinds[self._keys] == INTRA)
        )
        if not consistent:
            raise self._fail("frame index is inconsistent (truncated or corrupt)")

    def __len__(self) -> int:
        return len(self._kinds)

    @property
    def shape(self) -> tuple[int, int, int]:
        return (len(self), *self._shape)

    def __getitem__(self, index: FrameIndex) -> np.ndarray:
        positions, single = resolve_index(index, len(self))
        if single:
            return self._frame(positions[0])
        out = np.empty((len(positions), *self._shape), dtype=np.uint16)
        # Decode in keyframe order so each keyframe is decoded once.
        for slot in sorted(range(len(positions)), key=lambda s: (self._keys[positions[s]], s)):
            out[slot] = self._frame(positions[slot])
        return out

    def _frame(self, i: int) -> np.ndarray:
        try:
            if self._kinds[i] == INTRA:
                q, hole = self._decode_intra(i)
                self._remember(i, q)
            else:
                q, hole = self._decode_inter(i)
        except (lzma.LZMAError, ValueError) as exc:
            raise self._fail(f"frame {i} is corrupt ({exc})") from exc
        return dequantize(q, hole, self.step)

    def _raw(self, i: int) -> np.ndarray:
        blob = self._payload[self._offsets[i] : self._offsets[i + 1]].tobytes()
        if zlib.crc32(blob) != self._crcs[i]:
            raise ValueError("checksum mismatch")
        filters = [{"id": lzma.FILTER_LZMA2, "dict_size": self._dict_size}]
        return np.frombuffer(lzma.decompress(blob, format=lzma.FORMAT_RAW, filters=filters), np.uint8)

    def _split(self, raw: np.ndarray, n_modes: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """-> (zigzag residual, block modes, hole mask)."""
        h, w = self._shape
        if len(raw) < 2 * h * w + n_modes:
            raise ValueError("payload too short")
        z = (raw[: h * w].astype(np.uint16) | (raw[h * w : 2 * h * w].astype(np.uint16) << 8))
        modes = raw[2 * h * w : 2 * h * w + n_modes]
        hole = _mask_from_runs(raw[2 * h * w + n_modes :], self._shape)
        return z.reshape(h, w), modes, hole

    def _decode_intra(self, i: int) -> tuple[np.ndarray, np.ndarray]:
        z, _, hole = self._split(self._raw(i), 0)
        return _intra_reconstruct(_unzigzag(z)), hole

    def _decode_inter(self, i: int) -> tuple[np.ndarray, np.ndarray]:
        ref = self._reference(int(self._keys[i]))
        h, w = self._shape
        grid = (-(-h // BLOCK), -(-w // BLOCK))
        z, modes, hole = self._split(self._raw(i), grid[0] * grid[1])
        prediction = ref.predict(modes.reshape(grid))
        return (prediction + _unzigzag(z)) & 0xFFFF, hole

    def _reference(self, key: int) -> _Reference:
        if key not in self._references:
            q, _ = self._decode_intra(key)
            self._remember(key, q)
        self._references.move_to_end(key)
        return self._references[key]

    def _remember(self, key: int, q: np.ndarray) -> None:
        if key not in self._references:
            self._references[key] = _Reference(q)
            while len(self._references) > self._CACHED_KEYS:
                self._references.popitem(last=False)

    def close(self) -> None:
        self._references.clear()
        self._file.close()


class RmbzCodec(DepthCodec):
    """Our codec; ``step_mm`` is the quantisation step (odd; max error ``step_mm // 2``)."""

    file_suffix = ".rmbz.h5"

    def __init__(self, name: str = CODEC_ID, *, step_mm: int = 3):
        if step_mm < 1 or step_mm % 2 == 0:
            raise ValueError(f"step_mm must be a positive odd integer, got {step_mm}")
        self.name = name
        self.step_mm = step_mm

    def writer(self, path: str | Path, width: int, height: int) -> RmbzWriter:
        return RmbzWriter(path, width, height, step_mm=self.step_mm)

    def reader(self, path: str | Path) -> RmbzReader:
        """Reads any rmbz file: the step is stored in the file."""
        return RmbzReader(path)
