"""A small client for the rollout socket (what a speech / dialogue process would use)."""

from __future__ import annotations

import json
import socket
from typing import Any

from rmb_lerobot.rollout import protocol as P


class RolloutError(RuntimeError):
    """The server answered ``{"status": "error", ...}``; ``reply`` holds the whole answer."""

    def __init__(self, reply: dict[str, Any]):
        self.reply = reply
        self.code = reply.get("error")
        super().__init__(f"rollout server: {self.code}: {reply.get('message')}")


class RolloutClient:
    """One connection to a rollout server.

    ``timeout`` (seconds, ``None``: no limit) bounds connecting and every wait for a reply;
    running out raises ``TimeoutError``.

    >>> with RolloutClient("unix:/tmp/rmb.sock") as client:  # doctest: +SKIP
    ...     client.instruct("Put the banana in the blue basket.")  # {"status": "started", ...}
    ...     client.result()  # {"status": "success", "steps": 112, ...} when the episode ends
    """

    def __init__(self, address: P.Address | str, timeout: float | None = None):
        self.address = P.Address.parse(address) if isinstance(address, str) else address
        self.timeout = timeout
        self._sock = socket.socket(self.address.family, socket.SOCK_STREAM)
        self._sock.settimeout(timeout)
        try:
            self._sock.connect(self.address.sockaddr())
        except BaseException:
            self._sock.close()
            raise
        self._buffer = bytearray()

    def __enter__(self) -> RolloutClient:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        self._sock.close()

    # ------------------------------------------------------------------ raw lines
    def send_line(self, line: str) -> None:
        if "\n" in line or "\r" in line:
            raise ValueError(f"one line per message; {line!r} contains a line break")
        self._sock.sendall(line.encode("utf-8") + b"\n")

    def read_reply(self) -> dict[str, Any]:
        """The next reply line, parsed (``TimeoutError`` after ``timeout``)."""
        while b"\n" not in self._buffer:
            try:
                data = self._sock.recv(4096)
            except TimeoutError:
                raise TimeoutError(
                    f"no reply from {self.address} within {self.timeout} s"
                ) from None
            if not data:
                raise ConnectionError(f"{self.address} closed the connection")
            self._buffer += data
        end = self._buffer.index(b"\n")
        line = bytes(self._buffer[:end])
        del self._buffer[: end + 1]
        return json.loads(line)

    # ------------------------------------------------------------------ requests
    def instruct(self, instruction: str) -> dict[str, Any]:
        """Start an episode; returns the ``started`` reply (``RolloutError`` if refused)."""
        if P.is_done(instruction) or not instruction.strip():
            raise ValueError(f"not an instruction: {instruction!r}")
        self.send_line(instruction)
        return self._expect(P.STARTED)

    def result(self) -> dict[str, Any]:
        """Wait for the result of the episode this connection started (or ended)."""
        return self._expect(*P.RESULT_STATUSES)

    def done(self) -> dict[str, Any]:
        """End the running episode now; returns its result."""
        self.send_line(P.DONE)
        return self.result()

    def _expect(self, *statuses: str) -> dict[str, Any]:
        reply = self.read_reply()
        if reply.get("status") == P.ERROR:
            raise RolloutError(reply)
        if reply.get("status") not in statuses:
            raise RuntimeError(f"expected a {'/'.join(statuses)} reply, got {reply}")
        return reply
