"""The ``.rmbz`` file: a JSON header, appended frame packets, and a frame index at the end.

Layout (little-endian)::

    b"RMBZ" | u32 header length | header (UTF-8 JSON: codec, version, step, shape, ...)
    payload: per frame [group IDR if the frame starts a group] + P packet + hole mask
    index: u32 (N, 4) [packet size, mask size, group, crc32] then u32 (G, 2) [IDR size, crc32]
    footer: u64 index offset | u32 N | u32 G | u32 crc32 of header + index | b"ZBMR"

Written front to back as frames arrive (nothing to seek back to); the index is written last,
so a file whose writer did not finish has no footer and is rejected. Checksums cover every
payload byte (packets and masks per frame, IDRs per group) and the footer's covers header and
index (format version 1 files: the index only). Chosen over HDF5 because HDF5's own
structures cost ~8-10 KB per file, 4 % of a 220-frame clean depth stream.
"""

from __future__ import annotations

import json
import struct
import zlib
from pathlib import Path

import numpy as np

MAGIC = b"RMBZ"
END_MAGIC = b"ZBMR"
_FOOTER = struct.Struct("<QIII4s")


class ContainerWriter:
    def __init__(self, path: Path, header: dict):
        self.path = path
        self._file = open(path, "wb")  # noqa: SIM115 - closed in close()
        encoded = json.dumps(header, sort_keys=True).encode()
        self._file.write(MAGIC + struct.pack("<I", len(encoded)) + encoded)
        self._header_crc = zlib.crc32(encoded)
        self._frames: list[tuple[int, int, int, int]] = []
        self._groups: list[tuple[int, int]] = []

    def add_group(self, idr: bytes) -> int:
        """Append a group's IDR packet (just before its first frame); returns the group number."""
        self._file.write(idr)
        self._groups.append((len(idr), zlib.crc32(idr)))
        return len(self._groups) - 1

    def add_frame(self, packet: bytes, mask: bytes, group: int) -> None:
        self._file.write(packet)
        self._file.write(mask)
        self._frames.append((len(packet), len(mask), group, zlib.crc32(mask, zlib.crc32(packet))))

    def close(self) -> None:
        if self._file.closed:
            return
        try:
            offset = self._file.tell()
            frames = np.asarray(self._frames, dtype="<u4").reshape(-1, 4)
            groups = np.asarray(self._groups, dtype="<u4").reshape(-1, 2)
            index = frames.tobytes() + groups.tobytes()
            self._file.write(index)
            footer = (
                offset,
                len(frames),
                len(groups),
                zlib.crc32(index, self._header_crc),
                END_MAGIC,
            )
            self._file.write(_FOOTER.pack(*footer))
        finally:
            self._file.close()


class ContainerReader:
    """Header, index and byte ranges of an ``.rmbz`` file. Raises ValueError when malformed.

    ``header_checked`` says whether the footer's checksum covers the header (files written
    since format version 2) or the index only (version 1).
    """

    def __init__(self, path: Path):
        self._file = open(path, "rb")  # noqa: SIM115 - closed in close()
        try:
            self._read_structure()
        except BaseException:
            self._file.close()
            raise

    def _read_structure(self) -> None:
        f = self._file
        start = f.read(8)
        if len(start) < 8 or start[:4] != MAGIC:
            raise ValueError("no RMBZ magic at the start")
        (header_size,) = struct.unpack("<I", start[4:])
        raw_header = f.read(header_size)
        try:
            self.header = json.loads(raw_header)
            if not isinstance(self.header, dict):
                raise ValueError(f"header is {type(self.header).__name__}, not an object")
        except (UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise ValueError(f"unreadable header ({exc})") from exc
        payload_start = 8 + header_size
        size = f.seek(0, 2)
        if size < payload_start + _FOOTER.size:
            raise ValueError("file is truncated (no footer: its writer did not finish)")
        f.seek(size - _FOOTER.size)
        offset, n, g, crc, end = _FOOTER.unpack(f.read(_FOOTER.size))
        index_size = 4 * (4 * n + 2 * g)
        if end != END_MAGIC or offset < payload_start or offset + index_size + _FOOTER.size != size:
            raise ValueError("file is truncated or corrupt (bad footer: its writer did not finish)")
        f.seek(offset)
        index = f.read(index_size)
        self.header_checked = zlib.crc32(index, zlib.crc32(raw_header)) == crc
        if not self.header_checked and zlib.crc32(index) != crc:
            raise ValueError("header or frame index checksum mismatch")
        table = np.frombuffer(index, dtype="<u4").astype(np.int64)
        frames, groups = table[: 4 * n].reshape(n, 4), table[4 * n :].reshape(g, 2)
        self.frame_group, self.frame_crc = frames[:, 2], frames[:, 3]
        self.group_crc = groups[:, 1]
        group = self.frame_group
        if n and (group[0] != 0 or group[-1] != g - 1 or np.any(np.diff(group) > 1)):
            raise ValueError("frame groups are not consecutive")
        if np.any(np.diff(group) < 0) or (n == 0) != (g == 0):
            raise ValueError("frame groups are not consecutive")
        # Payload order: [IDR of a group starting here], packet, mask.
        starts_group = np.concatenate([[True], np.diff(group) == 1])[:n]
        idr = np.where(starts_group, groups[group, 0] if g else 0, 0)
        per_frame = idr + frames[:, 0] + frames[:, 1]
        frame_start = payload_start + np.concatenate([[0], np.cumsum(per_frame)])
        if frame_start[-1] != offset:
            raise ValueError("frame sizes do not add up to the payload size")
        self.group_range = np.stack([frame_start[:-1][starts_group], groups[:, 0]], axis=1)
        self.packet_range = np.stack([frame_start[:-1] + idr, frames[:, 0]], axis=1)
        self.mask_size = frames[:, 1]

    def read(self, start: int, size: int) -> bytes:
        self._file.seek(start)
        return self._file.read(size)

    def close(self) -> None:
        self._file.close()
