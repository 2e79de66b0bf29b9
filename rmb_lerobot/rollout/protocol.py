r"""The rollout socket's wire protocol: addresses, request lines and JSON reply lines.

Everything on the socket is newline-delimited UTF-8 text, one message per line (``\n``; a
trailing ``\r`` is dropped). A client sends:

- an **instruction** (any other non-empty line, e.g. ``Put the banana in the blue basket.``):
  starts an episode with it when no episode runs;
- ``done`` (any case, surrounding spaces ignored): ends the running episode now.

The server answers every line with one JSON object on one line, always with a ``status``:

- ``{"status": "started", "episode": 0, "instruction": "..."}`` to an instruction, then, when
  that episode ends (on its own or by a ``done`` from any connection), one result line to the
  same connection: ``{"status": "success" | "failure", "episode": 0, "steps": 37,
  "reason": "success" | "done" | "max_steps" | "terminated", "instruction": "..."}``;
  ``{"status": "aborted", "reason": "shutdown", ...}`` when the server stops mid-episode;
- the episode's result line to ``done`` (the instruction's connection gets it once, not twice);
- ``{"status": "error", "error": CODE, "message": "...", "request": "..."}`` to anything it
  cannot do; ``CODE`` is one of :data:`ERROR_CODES`.

``success`` means the env reported ``info["is_success"]`` at the episode's last step.
"""

from __future__ import annotations

import ipaddress
import json
import socket
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

DONE = "done"
MAX_LINE_BYTES = 4096  # an instruction is a sentence; longer lines are refused, not buffered

STARTED, SUCCESS, FAILURE, ABORTED, ERROR = "started", "success", "failure", "aborted", "error"
RESULT_STATUSES = (SUCCESS, FAILURE, ABORTED)
"""Statuses that end an episode: the last line a connection gets for it."""

ERROR_CODES = {
    "busy": "an episode is running; send 'done' first or wait for its result",
    "not_running": "'done' while no episode runs",
    "bad_instruction": "the env refused the instruction (e.g. Pick knows 18 instructions)",
    "empty": "an empty line",
    "bad_encoding": "the line is not UTF-8",
    "line_too_long": f"the line is longer than {MAX_LINE_BYTES} bytes",
    "too_many_connections": "the server holds its maximum of connections",
    "internal": "the policy or the env raised; the message says what",
}


# ------------------------------------------------------------------ addresses
@dataclass(frozen=True)
class Address:
    """Where the server listens: ``unix:PATH`` or ``tcp:HOST:PORT`` (``tcp:[::1]:PORT``)."""

    kind: Literal["unix", "tcp"]
    path: Path | None = None
    host: str | None = None
    port: int | None = None

    @classmethod
    def parse(cls, text: str) -> Address:
        kind, sep, rest = text.partition(":")
        if not sep or kind not in ("unix", "tcp") or not rest:
            raise ValueError(
                f"bad socket address {text!r}: expected unix:PATH or tcp:HOST:PORT "
                "(e.g. unix:/tmp/rmb.sock, tcp:127.0.0.1:5555)"
            )
        if kind == "unix":
            return cls("unix", path=Path(rest))
        host, sep, port = rest.rpartition(":")
        if not sep or not host or not port.isdigit() or int(port) > 65535:
            raise ValueError(f"bad tcp address {text!r}: expected tcp:HOST:PORT, PORT 0..65535")
        return cls("tcp", host=host.removeprefix("[").removesuffix("]"), port=int(port))

    def __str__(self) -> str:
        if self.kind == "unix":
            return f"unix:{self.path}"
        host = f"[{self.host}]" if self.host and ":" in self.host else self.host
        return f"tcp:{host}:{self.port}"

    @property
    def family(self) -> int:
        if self.kind == "unix":
            return socket.AF_UNIX
        return socket.AF_INET6 if self.host and ":" in self.host else socket.AF_INET

    def sockaddr(self) -> str | tuple[str, int]:
        return str(self.path) if self.kind == "unix" else (str(self.host), int(self.port or 0))

    def is_local(self) -> bool:
        """A Unix socket, or a TCP host whose every address is a loopback address."""
        if self.kind == "unix":
            return True
        try:
            infos = socket.getaddrinfo(self.host, self.port, type=socket.SOCK_STREAM)
        except socket.gaierror:
            return False
        addresses = {ipaddress.ip_address(info[4][0].split("%")[0]) for info in infos}
        return bool(addresses) and all(a.is_loopback for a in addresses)


# ------------------------------------------------------------------ lines
def reply_line(status: str, **fields: Any) -> bytes:
    """One reply: a JSON object with ``status`` first, on one line (JSON escapes newlines)."""
    return (json.dumps({"status": status, **fields}, ensure_ascii=False) + "\n").encode("utf-8")


def error_line(code: str, message: str, request: str | None = None) -> bytes:
    if code not in ERROR_CODES:
        raise ValueError(f"unknown error code {code!r}; one of {sorted(ERROR_CODES)}")
    return reply_line(ERROR, error=code, message=message, request=request)


def is_done(line: str) -> bool:
    return line.strip().lower() == DONE


class LineBuffer:
    """Splits a byte stream into protocol lines; a line over :data:`MAX_LINE_BYTES` is
    reported once (as ``None``) and its bytes dropped up to its newline."""

    def __init__(self, max_bytes: int = MAX_LINE_BYTES):
        self.max_bytes = max_bytes
        self._buffer = bytearray()
        self._discarding = False

    def feed(self, data: bytes) -> list[bytes | None]:
        r"""The complete lines in ``data`` (without ``\n`` / ``\r\n``), ``None`` for each
        line that was too long."""
        lines: list[bytes | None] = []
        self._buffer += data
        while True:
            end = self._buffer.find(b"\n")
            if end < 0:
                if len(self._buffer) > self.max_bytes:
                    if not self._discarding:
                        lines.append(None)
                    self._discarding = True
                    self._buffer.clear()
                return lines
            line = bytes(self._buffer[:end]).removesuffix(b"\r")
            del self._buffer[: end + 1]
            if self._discarding:
                self._discarding = False  # the rest of the overlong line
            elif len(line) > self.max_bytes:
                lines.append(None)
            else:
                lines.append(line)
