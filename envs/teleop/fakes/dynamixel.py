"""A fake chain of Dynamixel servos on a pseudo-terminal, speaking protocol 2.0.

The real ``dynamixel-sdk`` opens :attr:`FakeDynamixelChain.path` (the pty's slave side) as
its serial port, unmodified; a thread here answers on the master side as servos on a bus
would: instruction packets ``FF FF FD 00 | ID | LEN_L LEN_H | INST | params | CRC_L CRC_H``
(byte-stuffed: ``FF FF FD`` inside the body is followed by an extra ``FD``), status packets
with instruction ``0x55`` and an error byte. Supported: PING, READ, WRITE and SYNC_READ
(each listed servo that exists answers in turn; an absent ID stays silent, as on a real bus,
so the SDK times out). A packet with a bad CRC is answered with error 3 (CRC error).

Each servo has a 256-byte control table (an X-series layout: torque enable at 64, present
position at 132 as a little-endian signed 32-bit count, 4096 counts per turn); tests move a
servo with :meth:`FakeDynamixelChain.set_position`.
"""

from __future__ import annotations

import contextlib
import os
import select
import struct
import threading
import tty
from collections import Counter
from collections.abc import Mapping

HEADER = bytes((0xFF, 0xFF, 0xFD, 0x00))
BROADCAST_ID = 0xFE
INST_PING = 0x01
INST_READ = 0x02
INST_WRITE = 0x03
INST_STATUS = 0x55
INST_SYNC_READ = 0x82
ERR_INSTRUCTION = 0x02
ERR_CRC = 0x03
ERR_ACCESS = 0x07

ADDR_TORQUE_ENABLE = 64
ADDR_PRESENT_POSITION = 132
TABLE_SIZE = 256
MODEL_XL330_M288 = 1200  # model number a PING reports
FIRMWARE_VERSION = 52


def crc16(data: bytes) -> int:
    """Dynamixel protocol 2.0's CRC-16 (polynomial 0x8005, initial 0, not reflected).

    Args:
        data: The packet from the first header byte up to (not including) the CRC.

    Returns:
        The 16-bit CRC.
    """
    crc = 0
    for byte in data:
        crc ^= byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x8005) if crc & 0x8000 else crc << 1
            crc &= 0xFFFF
    return crc


def stuff(body: bytes) -> bytes:
    """Byte-stuff a packet body: every ``FF FF FD`` gets an extra ``FD`` after it.

    Args:
        body: Instruction (or status) byte onwards, without the CRC.

    Returns:
        The stuffed body.
    """
    out = bytearray()
    for byte in body:
        out.append(byte)
        if byte == 0xFD and len(out) >= 3 and out[-3:-1] == b"\xff\xff":
            out.append(0xFD)
    return bytes(out)


def unstuff(body: bytes) -> bytes:
    """Undo :func:`stuff`: drop the ``FD`` that follows each ``FF FF FD``.

    Args:
        body: A stuffed body.

    Returns:
        The body as sent.
    """
    out = bytearray()
    i = 0
    while i < len(body):
        out.append(body[i])
        if body[i] == 0xFD and len(out) >= 3 and out[-3:-1] == b"\xff\xff":
            i += 1  # the stuffing byte
        i += 1
    return bytes(out)


def packet(dxl_id: int, body: bytes) -> bytes:
    """A complete protocol 2.0 packet around an (unstuffed) body.

    Args:
        dxl_id: The servo ID (or 0xFE, broadcast).
        body: Instruction byte and parameters (a status: 0x55, error, parameters).

    Returns:
        Header, ID, length, stuffed body and CRC.
    """
    stuffed = stuff(body)
    head = HEADER + bytes((dxl_id,)) + struct.pack("<H", len(stuffed) + 2) + stuffed
    return head + struct.pack("<H", crc16(head))


class FakeServo:
    """One servo's control table.

    Args:
        dxl_id: Its ID on the bus (0..252).
        position: Initial present position (raw counts).
    """

    def __init__(self, dxl_id: int, position: int = 2048):
        if not 0 <= dxl_id <= 252:
            raise ValueError(f"Dynamixel ID must be in 0..252, got {dxl_id}")
        self.id = dxl_id
        self.table = bytearray(TABLE_SIZE)
        self.table[0:2] = struct.pack("<H", MODEL_XL330_M288)
        self.table[6] = FIRMWARE_VERSION
        self.table[7] = dxl_id
        self.position = position

    @property
    def position(self) -> int:
        """Present position (raw counts, signed)."""
        return struct.unpack_from("<i", self.table, ADDR_PRESENT_POSITION)[0]

    @position.setter
    def position(self, raw: int) -> None:
        struct.pack_into("<i", self.table, ADDR_PRESENT_POSITION, int(raw))

    def read(self, address: int, length: int) -> bytes | None:
        """The bytes at ``address``, or None when the range lies outside the table."""
        if address < 0 or length < 0 or address + length > TABLE_SIZE:
            return None
        return bytes(self.table[address : address + length])


class FakeDynamixelChain:
    """Servos on a pty that ``dynamixel_sdk.PortHandler(chain.path)`` talks to.

    Use as a context manager (or :meth:`start` / :meth:`close`). The pty's slave side stays
    open here as well, so the port survives the SDK closing and reopening it (its
    ``setBaudRate`` does).

    Args:
        positions: Raw present position by servo ID.

    Attributes:
        servos: The servos by ID.
        received: Instruction packets handled, by instruction byte (``INST_SYNC_READ``...).
    """

    def __init__(self, positions: Mapping[int, int]):
        self.servos = {dxl_id: FakeServo(dxl_id, raw) for dxl_id, raw in positions.items()}
        self.received: Counter[int] = Counter()
        self._lock = threading.Lock()
        self._master, self._slave = os.openpty()
        tty.setraw(self._slave)  # no echo, no line discipline before the SDK configures it
        self.path = os.ttyname(self._slave)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._serve, name="fake-dynamixel", daemon=True)
        self._buffer = bytearray()

    def start(self) -> FakeDynamixelChain:
        """Start answering; returns self."""
        self._thread.start()
        return self

    def close(self) -> None:
        """Stop answering and close the pty (safe to call twice)."""
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout=5)
        for fd in (self._master, self._slave):
            with contextlib.suppress(OSError):
                os.close(fd)

    def __enter__(self) -> FakeDynamixelChain:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.close()

    def set_position(self, dxl_id: int, raw: int) -> None:
        """Move a servo (as a hand moving the leader arm would).

        Args:
            dxl_id: The servo.
            raw: Its new present position (raw counts).
        """
        with self._lock:
            self.servos[dxl_id].position = raw

    def set_positions(self, positions: Mapping[int, int]) -> None:
        """Move several servos at once (one bus snapshot sees all or none of the change)."""
        with self._lock:
            for dxl_id, raw in positions.items():
                self.servos[dxl_id].position = raw

    # ------------------------------------------------------------------ the bus
    def _serve(self) -> None:
        while not self._stop.is_set():
            try:
                ready, _, _ = select.select([self._master], [], [], 0.05)
                if not ready:
                    continue
                chunk = os.read(self._master, 4096)
            except OSError:
                return  # closed
            self._buffer.extend(chunk)
            for dxl_id, body, crc_ok in self._packets():
                reply = self._answer(dxl_id, body, crc_ok)
                if reply:
                    os.write(self._master, reply)

    def _packets(self) -> list[tuple[int, bytes, bool]]:
        """Complete packets in the buffer (garbage before a header is dropped)."""
        found = []
        while True:
            start = self._buffer.find(HEADER)
            if start < 0:
                del self._buffer[: max(0, len(self._buffer) - 3)]
                return found
            del self._buffer[:start]
            if len(self._buffer) < 7:
                return found
            length = struct.unpack_from("<H", self._buffer, 5)[0]
            total = 7 + length
            if len(self._buffer) < total:
                return found
            raw = bytes(self._buffer[:total])
            del self._buffer[:total]
            crc_ok = crc16(raw[:-2]) == struct.unpack_from("<H", raw, total - 2)[0]
            found.append((raw[4], unstuff(raw[7:-2]), crc_ok))

    def _status(self, dxl_id: int, error: int, params: bytes = b"") -> bytes:
        return packet(dxl_id, bytes((INST_STATUS, error)) + params)

    def _answer(self, dxl_id: int, body: bytes, crc_ok: bool) -> bytes:
        if not body:
            return b""
        instruction, params = body[0], body[1:]
        with self._lock:
            self.received[instruction] += 1
            if not crc_ok:
                return self._status(dxl_id, ERR_CRC) if dxl_id in self.servos else b""
            if instruction == INST_SYNC_READ and dxl_id == BROADCAST_ID:
                return self._sync_read(params)
            targets = sorted(self.servos) if dxl_id == BROADCAST_ID else [dxl_id]
            replies = b""
            for target in targets:
                servo = self.servos.get(target)
                if servo is None:
                    continue  # nobody home: silence, as on a real bus
                replies += self._answer_one(servo, instruction, params)
            return replies if (dxl_id != BROADCAST_ID or instruction == INST_PING) else b""

    def _answer_one(self, servo: FakeServo, instruction: int, params: bytes) -> bytes:
        if instruction == INST_PING:
            return self._status(servo.id, 0, bytes(servo.table[0:2]) + bytes((servo.table[6],)))
        if instruction == INST_READ and len(params) == 4:
            address, length = struct.unpack("<HH", params)
            data = servo.read(address, length)
            if data is None:
                return self._status(servo.id, ERR_ACCESS)
            return self._status(servo.id, 0, data)
        if instruction == INST_WRITE and len(params) >= 2:
            address = struct.unpack_from("<H", params)[0]
            data = params[2:]
            if servo.read(address, len(data)) is None:
                return self._status(servo.id, ERR_ACCESS)
            servo.table[address : address + len(data)] = data
            return self._status(servo.id, 0)
        return self._status(servo.id, ERR_INSTRUCTION)

    def _sync_read(self, params: bytes) -> bytes:
        if len(params) < 4:
            return b""
        address, length = struct.unpack_from("<HH", params)
        replies = b""
        for dxl_id in params[4:]:
            servo = self.servos.get(dxl_id)
            if servo is None:
                continue
            data = servo.read(address, length)
            replies += self._status(dxl_id, 0 if data is not None else ERR_ACCESS, data or b"")
        return replies
