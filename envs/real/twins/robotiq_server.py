"""A real TCP server on loopback speaking the Robotiq URCap protocol, backed by a twin's gripper.

It answers what :class:`~rmb_lerobot.envs.real.drivers.robotiq.RobotiqGripper` (and any other
client of the URCap socket) sends: ``SET <VAR> <int> ...`` -> ``ack``, ``GET <VAR>`` ->
``<VAR> <int>``, with the gripper's activation states (``STA`` 0 reset, 1 activating, 3 active)
and fault register (``FLT``). A move (``GTO 1``) before activation is refused with fault 0x07,
as the gripper does. Positions come from the MuJoCo gripper (RMB's measured value, 0..255).

Fault hooks for tests: :meth:`RobotiqServer.inject_fault` (a fault code, the gripper stops
obeying moves) and :meth:`RobotiqServer.drop_connections` (every client is disconnected and
new ones are refused, like an unplugged controller).
"""

from __future__ import annotations

import contextlib
import logging
import socket
import threading
import time

from rmb_lerobot.envs.real.twins.sim import ArmSim

log = logging.getLogger(__name__)

_WRITABLE = ("ACT", "GTO", "ATR", "ADR", "POS", "SPE", "FOR")
_READABLE = (*_WRITABLE, "STA", "PRE", "OBJ", "FLT")
_AT_POSITION = 4  # |measured - requested| (0..255) within which OBJ reads 3 (at position)
_NO_ACTIVATION = 0x07


class RobotiqServer:
    """The URCap gripper socket of a twin controller.

    Args:
        sim: The twin arm whose gripper actuator this drives (command 0 open .. 255 closed).
        host: Loopback address to listen on.
        port: Port (0: any free port; read :attr:`port`).
        activation_s: How long ``STA`` stays 1 (activating) after ``ACT 1``.
    """

    def __init__(
        self, sim: ArmSim, host: str = "127.0.0.1", port: int = 0, activation_s: float = 0.3
    ):
        self._sim = sim
        self._activation_s = activation_s
        self._regs = dict.fromkeys(_WRITABLE, 0)
        self._regs.update(SPE=255, FOR=255)
        self._pre = 0
        self._fault = 0
        self._active_at: float | None = None  # when activation completes
        self._lock = threading.Lock()
        self._refusing = False
        self._clients: list[socket.socket] = []
        self._listener = socket.create_server((host, port))
        self._listener.settimeout(0.1)
        self.host, self.port = self._listener.getsockname()[:2]
        self._closing = threading.Event()
        self._thread = threading.Thread(target=self._serve, name="robotiq-twin", daemon=True)
        self._thread.start()

    # ------------------------------------------------------------------ hooks
    def inject_fault(self, code: int = 0x0E) -> None:
        """Make the gripper report fault ``code`` (default 0x0E, overcurrent) and stop it."""
        with self._lock:
            self._fault = code
        self._sim.set_gripper(self._sim.read().gripper)

    def drop_connections(self) -> None:
        """Disconnect every client and refuse new ones (until :meth:`accept_connections`)."""
        with self._lock:
            self._refusing = True
            clients, self._clients = self._clients, []
        for client in clients:
            _close(client)

    def accept_connections(self) -> None:
        """Accept clients again after :meth:`drop_connections`."""
        with self._lock:
            self._refusing = False

    def reset(self) -> None:
        """Power-on state: not activated, no fault, accepting clients (tests)."""
        with self._lock:
            self._regs = dict.fromkeys(_WRITABLE, 0)
            self._regs.update(SPE=255, FOR=255)
            self._pre = self._fault = 0
            self._active_at = None
            self._refusing = False

    @property
    def status(self) -> int:
        """``STA``: 0 reset, 1 activating, 3 active."""
        with self._lock:
            return self._status()

    def _status(self) -> int:
        if self._regs["ACT"] == 0 or self._active_at is None:
            return 0
        return 3 if time.monotonic() >= self._active_at else 1

    # ------------------------------------------------------------------ server
    def _serve(self) -> None:
        while not self._closing.is_set():
            try:
                client, _ = self._listener.accept()
            except TimeoutError:
                continue
            except OSError:
                return
            with self._lock:
                refusing = self._refusing
                if not refusing:
                    self._clients.append(client)
            if refusing:
                _close(client)
                continue
            threading.Thread(target=self._handle, args=(client,), daemon=True).start()

    def _handle(self, client: socket.socket) -> None:
        buffer = b""
        client.settimeout(0.2)
        try:
            while not self._closing.is_set():
                try:
                    chunk = client.recv(256)
                except TimeoutError:
                    continue
                if not chunk:
                    return
                buffer += chunk
                while b"\n" in buffer:
                    line, buffer = buffer.split(b"\n", 1)
                    reply = self.answer(line.decode("ascii", errors="replace").strip())
                    client.sendall(reply.encode("ascii") + b"\n")
        except OSError:
            return
        finally:
            with self._lock:
                if client in self._clients:
                    self._clients.remove(client)
            _close(client)

    def answer(self, line: str) -> str:
        """The reply to one request line (``ack``, ``<VAR> <int>`` or ``?``).

        Args:
            line: The request without its newline.

        Returns:
            The reply without its newline.
        """
        words = line.split()
        if len(words) == 2 and words[0] == "GET" and words[1] in _READABLE:
            return f"{words[1]} {self._get(words[1])}"
        if len(words) >= 3 and words[0] == "SET" and len(words) % 2 == 1:
            pairs = list(zip(words[1::2], words[2::2], strict=True))
            if all(n in _WRITABLE and v.isdigit() and int(v) <= 255 for n, v in pairs):
                self._set({n: int(v) for n, v in pairs})
                return "ack"
        return "?"

    def _get(self, name: str) -> int:
        with self._lock:
            if name == "STA":
                return self._status()
            if name == "FLT":
                return self._fault
            if name == "PRE":
                return self._pre
            if name not in ("POS", "OBJ"):
                return self._regs[name]
        measured = round(min(max(self._sim.read().gripper, 0.0), 255.0))
        if name == "POS":
            return measured
        with self._lock:
            if self._regs["GTO"] == 0:
                return 3
            return 3 if abs(measured - self._pre) <= _AT_POSITION else 0

    def _set(self, values: dict[str, int]) -> None:
        move: int | None = None
        stop = False
        with self._lock:
            if values.get("ACT") == 0:
                self._active_at = None
            elif values.get("ACT") == 1 and self._regs["ACT"] == 0:
                self._active_at = time.monotonic() + self._activation_s
            self._regs.update(values)
            if values.get("ACT") == 0:
                self._fault = 0 if self._fault == _NO_ACTIVATION else self._fault
            if "POS" in values:
                self._pre = values["POS"]
            if self._regs["GTO"] == 1 and ("GTO" in values or "POS" in values):
                if self._status() != 3:
                    self._fault = self._fault or _NO_ACTIVATION
                elif self._fault == 0:
                    move = self._pre
            elif values.get("GTO") == 0:
                stop = True
        if move is not None:
            self._sim.set_gripper(move)
        elif stop:
            self._sim.set_gripper(self._sim.read().gripper)

    def close(self) -> None:
        """Stop serving and disconnect every client; safe to call twice."""
        self._closing.set()
        _close(self._listener)
        self.drop_connections()
        if self._thread.is_alive():
            self._thread.join(timeout=1.0)


def _close(sock: socket.socket) -> None:
    with contextlib.suppress(OSError):
        sock.shutdown(socket.SHUT_RDWR)
    with contextlib.suppress(OSError):
        sock.close()
