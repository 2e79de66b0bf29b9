"""A client for the Robotiq 2F-85 gripper over the UR controller's URCap socket (TCP 63352).

The Robotiq URCap on a UR controller listens on TCP port 63352 and speaks ASCII lines:

- ``SET <VAR> <int> [<VAR> <int> ...]\\n`` sets one or more variables; the answer is ``ack``.
- ``GET <VAR>\\n`` reads one; the answer is ``<VAR> <int>``.

Variables: ``ACT`` (activate), ``GTO`` (go to the requested position), ``ATR`` (automatic
release), ``POS`` (requested position on SET, measured position on GET), ``SPE`` (speed),
``FOR`` (force), all 0..255 (``POS`` 0 = open, 255 = closed); read-only ``STA`` (0 reset,
1 activating, 3 active), ``PRE`` (the position request echoed), ``OBJ`` (0 moving, 1 stopped
by an object while opening, 2 while closing, 3 at the requested position) and ``FLT`` (fault
code, 0 none). Activation: clear ``ACT`` and ``ATR`` until ``ACT`` and ``STA`` read 0, then set
``ACT 1`` and wait for ``STA 3``.

Every failure is a :class:`~rmb_lerobot.envs.real.driver.DriverError` naming ``host:port``:
:class:`~rmb_lerobot.envs.real.driver.ConnectionLost` when the socket fails, closes or times
out, :class:`~rmb_lerobot.envs.real.driver.GripperFault` when the gripper answers wrongly,
reports a fault or does not activate.
"""

from __future__ import annotations

import contextlib
import socket
import threading
import time

from rmb_lerobot.envs.real.driver import ConnectionLost, GripperFault

URCAP_PORT = 63352
"""The Robotiq URCap's gripper socket on the UR controller."""

# Robotiq 2F-85 fault codes (FLT) and what they mean (the gripper's manual, section 4.7.2).
FAULTS: dict[int, str] = {
    0x05: "action delayed: the activation (reactivation) must complete first",
    0x07: "the activation bit must be set before any action",
    0x08: "maximum operating temperature exceeded",
    0x09: "no communication for at least 1 s",
    0x0A: "under minimum operating voltage",
    0x0B: "automatic release in progress",
    0x0C: "internal processor fault",
    0x0D: "activation fault",
    0x0E: "overcurrent triggered",
    0x0F: "automatic release completed",
}

STA_RESET, STA_ACTIVATING, STA_ACTIVE = 0, 1, 3
_MAX_REPLY = 64  # bytes; a reply longer than this is not the URCap's


def fault_text(code: int) -> str:
    """What a Robotiq fault code means.

    Args:
        code: The ``FLT`` value.

    Returns:
        A short description (``"unknown fault"`` for codes the manual does not list).
    """
    return FAULTS.get(code, "unknown fault")


class RobotiqGripper:
    """One Robotiq 2F-85 behind a URCap socket.

    Thread-safe: one request at a time on the socket.

    Args:
        host: The UR controller's address.
        port: The URCap gripper port.
        timeout_s: Socket timeout (s) for connecting and for each reply.
    """

    def __init__(self, host: str, port: int = URCAP_PORT, timeout_s: float = 2.0):
        self.host = host
        self.port = port
        self.timeout_s = timeout_s
        self._sock: socket.socket | None = None
        self._buffer = b""
        self._lock = threading.Lock()

    @property
    def address(self) -> str:
        """``host:port`` for messages."""
        return f"{self.host}:{self.port}"

    @property
    def connected(self) -> bool:
        """Whether the socket is open (it may still have dropped on the other side)."""
        return self._sock is not None

    def connect(self) -> None:
        """Open the socket.

        Raises:
            ConnectionLost: If nothing answers at ``host:port`` within the timeout.
        """
        self.close()
        try:
            self._sock = socket.create_connection((self.host, self.port), timeout=self.timeout_s)
        except OSError as error:
            raise ConnectionLost(
                f"Robotiq gripper at {self.address}: cannot connect: {error}"
            ) from error
        self._sock.settimeout(self.timeout_s)
        self._buffer = b""

    def close(self) -> None:
        """Close the socket; safe to call at any time, also twice."""
        sock, self._sock = self._sock, None
        if sock is not None:
            with contextlib.suppress(OSError):
                sock.close()

    # ------------------------------------------------------------------ protocol
    def _request(self, line: str) -> str:
        with self._lock:
            if self._sock is None:
                raise ConnectionLost(f"Robotiq gripper at {self.address}: not connected")
            try:
                self._sock.sendall(line.encode("ascii") + b"\n")
                return self._read_line()
            except TimeoutError as error:
                self.close()
                raise ConnectionLost(
                    f"Robotiq gripper at {self.address}: no reply to {line!r} within "
                    f"{self.timeout_s} s"
                ) from error
            except OSError as error:
                self.close()
                raise ConnectionLost(
                    f"Robotiq gripper at {self.address}: connection lost during {line!r}: {error}"
                ) from error

    def _read_line(self) -> str:
        assert self._sock is not None
        while b"\n" not in self._buffer:
            chunk = self._sock.recv(_MAX_REPLY)
            if not chunk:
                self.close()
                raise ConnectionLost(
                    f"Robotiq gripper at {self.address}: the controller closed the connection"
                )
            self._buffer += chunk
            if len(self._buffer) > _MAX_REPLY and b"\n" not in self._buffer:
                raise GripperFault(
                    f"Robotiq gripper at {self.address}: unexpected reply {self._buffer[:32]!r}"
                )
        line, self._buffer = self._buffer.split(b"\n", 1)
        return line.decode("ascii", errors="replace").strip()

    def set(self, **values: int) -> None:
        """Set variables in one ``SET`` line (``set(POS=255, SPE=50, FOR=10, GTO=1)``).

        Args:
            **values: Variable name (upper case) -> integer value 0..255.

        Raises:
            ValueError: On a value outside 0..255.
            GripperFault: If the gripper does not answer ``ack``.
            ConnectionLost: If the socket fails.
        """
        parts = []
        for name, value in values.items():
            if not 0 <= int(value) <= 255:
                raise ValueError(f"Robotiq {name} must be 0..255, got {value}")
            parts.append(f"{name} {int(value)}")
        command = "SET " + " ".join(parts)
        reply = self._request(command)
        if reply != "ack":
            raise GripperFault(
                f"Robotiq gripper at {self.address}: answered {reply!r} to {command!r}"
            )

    def get(self, name: str) -> int:
        """Read one variable.

        Args:
            name: The variable (``"POS"``, ``"STA"``, ``"FLT"``, ...).

        Returns:
            Its integer value.

        Raises:
            GripperFault: If the reply is not ``<name> <int>``.
            ConnectionLost: If the socket fails.
        """
        reply = self._request(f"GET {name}")
        head, _, value = reply.partition(" ")
        if head != name or not value.strip().lstrip("-").isdigit():
            raise GripperFault(
                f"Robotiq gripper at {self.address}: answered {reply!r} to 'GET {name}'"
            )
        return int(value)

    # ------------------------------------------------------------------ operations
    def check_fault(self) -> None:
        """Raise if the gripper reports a fault.

        Raises:
            GripperFault: Naming the ``FLT`` code and its meaning.
        """
        code = self.get("FLT")
        if code != 0:
            raise GripperFault(
                f"Robotiq gripper at {self.address}: fault 0x{code:02X} ({fault_text(code)})"
            )

    def is_active(self) -> bool:
        """Whether the gripper is activated (``ACT 1`` and ``STA 3``)."""
        return self.get("ACT") == 1 and self.get("STA") == STA_ACTIVE

    def activate(self, timeout_s: float = 5.0, poll_s: float = 0.02) -> None:
        """Activate the gripper unless it is active already (reset, then ``ACT 1``).

        Args:
            timeout_s: How long each phase (reset, activation) may take.
            poll_s: Polling period.

        Raises:
            GripperFault: If a phase does not finish in time (naming ``STA`` and ``FLT``).
            ConnectionLost: If the socket fails.
        """
        if self.is_active():
            return
        self.set(ACT=0)
        self.set(ATR=0)
        self._wait(
            lambda: self.get("ACT") == 0 and self.get("STA") == STA_RESET,
            "reset",
            timeout_s,
            poll_s,
        )
        self.set(ACT=1)
        self._wait(lambda: self.get("STA") == STA_ACTIVE, "activation", timeout_s, poll_s)

    def _wait(self, done, phase: str, timeout_s: float, poll_s: float) -> None:
        deadline = time.monotonic() + timeout_s
        while not done():
            if time.monotonic() > deadline:
                sta, flt = self.get("STA"), self.get("FLT")
                fault = fault_text(flt) if flt else "none"
                raise GripperFault(
                    f"Robotiq gripper at {self.address}: {phase} did not finish within "
                    f"{timeout_s} s (STA {sta}, FLT 0x{flt:02X}: {fault})"
                )
            time.sleep(poll_s)

    def move(self, position: int, speed: int, force: int) -> None:
        """Start a move to ``position`` (0 open .. 255 closed) without waiting.

        Args:
            position: Requested position, 0..255.
            speed: Speed, 0..255.
            force: Force, 0..255.

        Raises:
            GripperFault: If the gripper refuses the command.
            ConnectionLost: If the socket fails.
        """
        self.set(POS=position, SPE=speed, FOR=force, GTO=1)

    def position(self) -> int:
        """The measured position, 0 (open) .. 255 (closed)."""
        return self.get("POS")

    def stop(self) -> None:
        """Stop a move in progress (``GTO 0``)."""
        self.set(GTO=0)
