"""``rmbz``: our depth codec. Max error 1 mm, smaller than RMB's depth video, 2 decodes per frame.

How (numbers in benchmarks/RESULTS.md):

- Quantisation ``q = round(mm / 3)`` bounds the error by 1 mm and drops log2(3) bits of sensor
  noise per pixel that a lossless codec has to store. ``step_mm=1`` (``rmbz-exact``) is lossless.
- Dropouts (0 = no data) are stored once per frame as a run-length mask and replaced in the
  image by the prediction, so they cost no residual and decode to exactly 0.
- Frames are grouped; each group has a reference image (its first frame, box-averaged in the
  16x16 blocks where that predicts the next frame better: sensor noise is averaged away, clean
  rendered depth stays exact). Every frame is a lossless H.264 P-frame predicted from the
  reference only (see :mod:`rmbz_h264`), so static parts cost almost nothing, x264's motion
  compensation handles moving parts, and frame i decodes from two packets instead of a chain.
- A new group starts when a reference built from the previous frame would make the current
  frame at least 40 % smaller and pay for its IDR within 30 frames. This is checked when frames
  have doubled in size since the last check, again on the next frame after a scene cut, and
  every 30 frames.

File: see :mod:`rmbz_container` (JSON header with codec, format version, quantisation step
and shape; packets appended as frames arrive; frame index and checksums at the end).
"""

from __future__ import annotations

import lzma
import zlib
from pathlib import Path

import av
import numpy as np

from rmb_lerobot.codecs.depth_base import DepthCodec, DepthReader, DepthWriter, as_depth_mm
from rmb_lerobot.codecs.indexing import FrameIndex, resolve_index
from rmb_lerobot.codecs.rmbz_arrays import (
    decode_mask,
    dequantize,
    encode_mask,
    fill_from_left,
    quantize,
    reference_image,
)
from rmb_lerobot.codecs.rmbz_container import ContainerReader, ContainerWriter
from rmb_lerobot.codecs.rmbz_h264 import PIX_FMT, PairDecoder, encode_pair
from rmb_lerobot.errors import RmbFormatError

CODEC_ID = "rmbz"
# 2: the footer's checksum covers the header too (a flipped digit of step_mm would otherwise
# rescale every depth silently). Version 1 files are still read.
FORMAT_VERSION = 2
READABLE_VERSIONS = (1, 2)
# A new group starts if a fresh reference makes the frame at most 60 % as big and the saving
# pays for the new IDR within CHECK_INTERVAL frames.
REFRESH_GAIN = 0.6
CHECK_INTERVAL = 30  # frames between refresh checks while frame sizes stay flat


class _Group:
    def __init__(self, number: int, reference: np.ndarray, idr: bytes):
        self.number = number
        self.reference = reference
        self.idr = idr
        self.check_size = 0  # a frame larger than this triggers a refresh check
        self.next_check = 0
        self.missed = False  # the last check found no better reference


class RmbzWriter(DepthWriter):
    """Encodes frames as they arrive; only the first frame waits for the second."""

    def __init__(
        self, path: str | Path, width: int, height: int, *, step_mm: int, preset: str = "slow"
    ):
        self.path = Path(path)
        self.shape = (int(height), int(width))
        if min(self.shape) <= 0:
            raise RmbFormatError(
                f"bad frame size {width}x{height}; expected positive width and height",
                path=self.path,
            )
        self.step = step_mm
        self.preset = preset
        header = {
            "codec": CODEC_ID,
            "format_version": FORMAT_VERSION,
            "step_mm": step_mm,
            "height": self.shape[0],
            "width": self.shape[1],
            "video": f"lossless H.264 pairs (group IDR + frame P), {PIX_FMT}, 10-bit fold",
            "mask": "raw LZMA2 of LEB128 run lengths (valid first); empty = no holes",
        }
        self._container = ContainerWriter(self.path, header)
        self._group: _Group | None = None
        self._pending: tuple[np.ndarray, np.ndarray, bytes] | None = None
        self._previous: np.ndarray | None = None
        self._received = 0
        self._closed = False

    def __len__(self) -> int:
        return self._received

    def write(self, frame: np.ndarray) -> None:
        if self._closed:
            raise RmbFormatError("writer is closed; expected no more frames", path=self.path)
        mm = as_depth_mm(frame, self.shape, self.path, self._received)
        self._received += 1
        hole = mm == 0
        q = fill_from_left(quantize(mm, self.step), hole)
        current = (q, hole, encode_mask(hole))
        if self._group is None and self._pending is None:
            self._pending = current  # the reference is chosen with the help of frame 2
            return
        if self._group is None:
            first, self._pending = self._pending, None
            self._store(*first, new_reference=reference_image(first[0], q, hole))
            self._store(*current)
        else:
            self._store(*current, may_refresh=True)
        self._previous = q

    def _start_group(self, reference: np.ndarray, idr: bytes) -> None:
        self._group = _Group(self._container.add_group(idr), reference, idr)

    def _store(
        self,
        q: np.ndarray,
        hole: np.ndarray,
        mask: bytes,
        *,
        new_reference: np.ndarray | None = None,
        may_refresh: bool = False,
    ) -> None:
        """Encode one frame against the group reference (or start a group with a new one)."""
        reference = self._group.reference if new_reference is None else new_reference
        idr, packet = encode_pair(reference, np.where(hole, reference, q), self.preset)
        if new_reference is not None or idr != self._group.idr:
            # A changed IDR was never seen; the check keeps files correct if x264 changed.
            self._start_group(reference, idr)
        elif may_refresh and self._previous is not None and self._due(len(packet)):
            fresh = reference_image(self._previous, q, hole)
            fresh_idr, fresh_packet = encode_pair(fresh, np.where(hole, fresh, q), self.preset)
            saving = len(packet) - len(fresh_packet)
            if saving >= (1 - REFRESH_GAIN) * len(packet) and saving * CHECK_INTERVAL >= len(
                fresh_idr
            ):
                self._start_group(fresh, fresh_idr)
                packet = fresh_packet
            elif self._group.missed or len(packet) <= self._group.check_size:
                self._schedule_check(len(packet))
            else:  # frames grew but the previous frame is no better: a cut? retry once
                self._group.missed = True
        if not self._group.check_size:
            self._schedule_check(len(packet))
        self._container.add_frame(packet, mask, self._group.number)

    def _schedule_check(self, size: int) -> None:
        """Check for a better reference once frames double in size, or after a while."""
        self._group.check_size = 2 * size
        self._group.next_check = self._received + CHECK_INTERVAL
        self._group.missed = False

    def _due(self, size: int) -> bool:
        return size > self._group.check_size or self._received >= self._group.next_check

    def close(self) -> None:
        """Encode a lone first frame, then write the frame index (idempotent)."""
        if self._closed:
            return
        self._closed = True
        try:
            if self._pending is not None:
                first, self._pending = self._pending, None
                self._store(*first, new_reference=first[0])
        finally:
            self._container.close()


class RmbzReader(DepthReader):
    """Frame i = decode(group IDR, frame i's P packet) + hole mask. Not thread-safe."""

    def __init__(self, path: str | Path):
        self.path = Path(path)
        if not self.path.is_file():
            raise RmbFormatError("depth file not found; expected an .rmbz file", path=path)
        try:
            self._container = ContainerReader(self.path)
        except ValueError as exc:
            raise self._fail(str(exc)) from exc
        try:
            self._check_header(self._container.header)
        except BaseException:
            self._container.close()
            raise
        self._decoder = PairDecoder()
        self._idr_cache: tuple[int, bytes] | None = None

    def _fail(self, what: str) -> RmbFormatError:
        return RmbFormatError(f"{what}; expected an rmbz depth file", path=self.path)

    def _check_header(self, header: dict) -> None:
        if header.get("codec") != CODEC_ID:
            raise self._fail(f"codec is {header.get('codec')!r}, not {CODEC_ID!r}")
        version = header.get("format_version")
        if version not in READABLE_VERSIONS:
            raise self._fail(
                f"unsupported format_version {version!r} (this reader knows {READABLE_VERSIONS})"
            )
        if version >= 2 and not self._container.header_checked:
            raise self._fail("header checksum mismatch")
        try:
            self.step = int(header["step_mm"])
            self._shape = (int(header["height"]), int(header["width"]))
        except (KeyError, TypeError, ValueError) as exc:
            raise self._fail(f"header lacks step_mm/height/width ({exc})") from exc
        if self.step < 1 or min(self._shape) < 1:
            raise self._fail(f"header has step_mm {self.step} and shape {self._shape}")

    def __len__(self) -> int:
        return len(self._container.frame_group)

    @property
    def groups(self) -> np.ndarray:
        """Group (shared reference image) of every frame, for inspection."""
        return self._container.frame_group.copy()

    @property
    def shape(self) -> tuple[int, int, int]:
        return (len(self), *self._shape)

    def __getitem__(self, index: FrameIndex) -> np.ndarray:
        positions, single = resolve_index(index, len(self))
        if single:
            return self._frame(positions[0])
        out = np.empty((len(positions), *self._shape), dtype=np.uint16)
        for slot, i in enumerate(positions):
            out[slot] = self._frame(i)
        return out

    def _idr(self, group: int) -> bytes:
        if self._idr_cache is None or self._idr_cache[0] != group:
            idr = self._container.read(*self._container.group_range[group])
            if zlib.crc32(idr) != self._container.group_crc[group]:
                raise ValueError(f"checksum mismatch in the reference of group {group}")
            self._idr_cache = (group, idr)
        return self._idr_cache[1]

    def _frame(self, i: int) -> np.ndarray:
        c = self._container
        try:
            idr = self._idr(int(c.frame_group[i]))
            start, size = c.packet_range[i]
            blob = c.read(start, size + c.mask_size[i])
            if zlib.crc32(blob) != c.frame_crc[i]:
                raise ValueError("checksum mismatch")
            q = self._decoder.decode(idr, blob[:size])
            hole = decode_mask(blob[size:], self._shape)
        except (av.FFmpegError, lzma.LZMAError, ValueError) as exc:
            raise self._fail(f"frame {i} is corrupt ({exc})") from exc
        if q.shape != self._shape:
            raise self._fail(f"frame {i} decoded to {q.shape}, not {self._shape}")
        return dequantize(q, hole, self.step)

    def close(self) -> None:
        self._idr_cache = None
        self._container.close()


class RmbzCodec(DepthCodec):
    """Our codec; ``step_mm`` is the quantisation step (odd; max error ``step_mm // 2`` mm)."""

    file_suffix = ".rmbz"

    def __init__(self, name: str = CODEC_ID, *, step_mm: int = 3, preset: str = "slow"):
        if step_mm < 1 or step_mm % 2 == 0:
            raise ValueError(f"step_mm must be a positive odd integer, got {step_mm}")
        self.name = name
        self.step_mm = step_mm
        self.preset = preset

    def writer(self, path: str | Path, width: int, height: int) -> RmbzWriter:
        return RmbzWriter(path, width, height, step_mm=self.step_mm, preset=self.preset)

    def reader(self, path: str | Path) -> RmbzReader:
        """Reads any rmbz file: the step is stored in the file."""
        return RmbzReader(path)


__all__ = ["CODEC_ID", "RmbzCodec", "RmbzReader", "RmbzWriter"]
