"""The rollout server: one episode per instruction received on a local socket.

RMB's interactive demo (the paper's "Research Applications") keeps speech recognition and
language models in one process and robot control in another, joined by a Unix socket: the
dialogue process sends the instruction a user asked for, the rollout runs the
language-conditioned policy with it, and "done" ends the episode. :class:`RolloutServer` is
that robot-control side for any gymnasium env and any :class:`RolloutPolicy`, single-threaded:
between two env steps it reads the socket without waiting, and while idle it waits on it.
The protocol is in :mod:`rmb_lerobot.rollout.protocol`.
"""

from __future__ import annotations

import contextlib
import logging
import os
import selectors
import signal
import socket
import stat
import threading
from collections.abc import Callable, Iterator, Mapping
from dataclasses import asdict, dataclass, field
from typing import Any, Protocol, runtime_checkable

import gymnasium as gym
import numpy as np

from rmb_lerobot.rollout import protocol as P

logger = logging.getLogger(__name__)

IDLE_POLL_S = 0.5  # how long an idle server sleeps in select (stop() wakes it earlier)


@runtime_checkable
class RolloutPolicy(Protocol):
    """What the server needs from a policy: a fresh start per episode and one action per
    observation, given the episode's instruction (LeRobot's ``task``)."""

    def reset(self) -> None: ...

    def act(self, observation: Mapping[str, Any], instruction: str) -> np.ndarray: ...


@dataclass
class EpisodeResult:
    """How an episode ended (``status`` success / failure / aborted, or error)."""

    episode: int
    instruction: str
    status: str
    reason: str
    steps: int
    message: str | None = None  # for status "error": what raised

    def line(self) -> bytes:
        fields = {k: v for k, v in asdict(self).items() if k != "status" and v is not None}
        if self.status == P.ERROR:
            fields["error"] = "internal"
        return P.reply_line(self.status, **fields)


@dataclass(eq=False)  # hashed by identity
class _Connection:
    sock: socket.socket
    name: str
    lines: P.LineBuffer = field(default_factory=P.LineBuffer)


@dataclass
class _Episode:
    index: int
    instruction: str
    owner: _Connection | None
    observation: Mapping[str, Any]
    steps: int = 0
    success: bool = False
    done_by: list[_Connection] = field(default_factory=list)


def takes_instruction(env: gym.Env) -> bool:
    """Whether the env's ``reset`` accepts ``options={"instruction": ...}`` (our envs list
    their task's reset options; Pick takes its 18 instructions)."""
    task = getattr(env.unwrapped, "task", None)
    return "instruction" in getattr(task, "reset_options", ())


def env_step_limit(env: gym.Env) -> int | None:
    """The env's own episode length (gymnasium's ``TimeLimit``), if it has one."""
    spec_limit = env.spec.max_episode_steps if env.spec is not None else None
    limit = getattr(env, "_max_episode_steps", None) or spec_limit
    return int(limit) if limit else None


class RolloutServer:
    """Serve instructions on ``address`` and run one episode of ``env`` per instruction.

    ``max_steps`` caps each episode (default: the env's ``TimeLimit``; one of the two is
    required), ``episodes`` makes :meth:`serve` return after that many (default: until
    :meth:`stop`), episode ``k`` resets with seed ``seed + k`` (``seed=None``: unseeded). The
    instruction goes to the policy as its task and, when the env takes it (see
    :func:`takes_instruction`; ``env_instruction`` forces either way), to ``env.reset`` too.
    TCP addresses must be loopback unless ``allow_remote``: nothing here authenticates a
    client. A Unix socket is created readable and writable by its owner only.

    Use it as a context manager (``with RolloutServer(...) as server: server.serve()``): the
    socket is bound on entry and closed, with its file removed, on exit. Call :meth:`serve` in
    the thread that made the env (a MuJoCo env's OpenGL context belongs to that thread).
    """

    def __init__(
        self,
        env: gym.Env,
        policy: RolloutPolicy,
        address: P.Address | str,
        *,
        max_steps: int | None = None,
        episodes: int | None = None,
        seed: int | None = 0,
        env_instruction: bool | None = None,
        allow_remote: bool = False,
        max_connections: int = 8,
        send_timeout_s: float = 5.0,
        on_result: Callable[[EpisodeResult], None] | None = None,
    ):
        self.env = env
        self.policy = policy
        self.address = P.Address.parse(address) if isinstance(address, str) else address
        limits = [x for x in (max_steps, env_step_limit(env)) if x is not None]
        if not limits:
            raise ValueError("the env has no TimeLimit: give max_steps (--max-steps)")
        if min(limits) < 1:
            raise ValueError(f"max_steps must be at least 1, got {min(limits)}")
        self.max_steps = min(limits)
        if episodes is not None and episodes < 1:
            raise ValueError(f"episodes must be at least 1, got {episodes}")
        self.episodes = episodes
        self.seed = seed
        self.env_instruction = (
            takes_instruction(env) if env_instruction is None else env_instruction
        )
        if not allow_remote and not self.address.is_local():
            raise PermissionError(
                f"refusing to listen on {self.address}: not a loopback address, and the "
                "rollout socket has no authentication (anyone who reaches it moves the robot); "
                "use 127.0.0.1 / ::1 / a unix: socket, or force it with --allow-remote"
            )
        self.max_connections = max_connections
        self.send_timeout_s = send_timeout_s
        self.on_result = on_result
        self.results: list[EpisodeResult] = []
        self._listener: socket.socket | None = None
        self._socket_file: tuple[int, int] | None = None  # (st_dev, st_ino) of our socket file
        self._selector: selectors.BaseSelector | None = None
        self._stop = threading.Event()
        self._connections: dict[socket.socket, _Connection] = {}
        self._episode: _Episode | None = None
        self._next_index = 0
        self._next_conn = 0
        self._wake: tuple[socket.socket, socket.socket] | None = None  # stop() -> idle select

    # ------------------------------------------------------------------ lifecycle
    def __enter__(self) -> RolloutServer:
        self.open()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def open(self) -> None:
        """Bind and listen; ``self.address`` then holds the bound port of ``tcp:HOST:0``."""
        if self._listener is not None:
            return
        listener = socket.socket(self.address.family, socket.SOCK_STREAM)
        try:
            if self.address.kind == "unix":
                self._bind_unix(listener)
            else:
                listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
                listener.bind(self.address.sockaddr())
                port = listener.getsockname()[1]
                self.address = P.Address("tcp", host=self.address.host, port=port)
            listener.listen()
            listener.setblocking(False)
        except BaseException:
            listener.close()
            raise
        self._listener = listener
        self._wake = socket.socketpair()
        for sock in self._wake:
            sock.setblocking(False)
        self._selector = selectors.DefaultSelector()
        self._selector.register(listener, selectors.EVENT_READ, "listen")
        self._selector.register(self._wake[0], selectors.EVENT_READ, "wake")
        logger.info("listening on %s", self.address)

    def _bind_unix(self, listener: socket.socket) -> None:
        path = self.address.path
        assert path is not None
        if path.exists() or path.is_symlink():
            if not stat.S_ISSOCK(os.lstat(path).st_mode):
                raise FileExistsError(f"{path} exists and is not a socket; not replacing it")
            with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as probe:
                try:
                    probe.connect(str(path))
                except (ConnectionRefusedError, FileNotFoundError):
                    logger.warning("removing stale socket %s (no server behind it)", path)
                    path.unlink(missing_ok=True)
                else:
                    raise OSError(f"{path}: another server is listening on this socket")
        try:
            listener.bind(str(path))
        except OSError as err:
            raise OSError(f"cannot bind unix socket {path}: {err}") from err
        os.chmod(path, 0o600)
        info = os.stat(path)
        self._socket_file = (info.st_dev, info.st_ino)

    def stop(self) -> None:
        """Make :meth:`serve` return soon (thread- and signal-safe): a running episode ends
        as ``aborted`` at the next step."""
        self._stop.set()
        wake = self._wake
        if wake is not None:
            with contextlib.suppress(OSError):
                wake[1].send(b"x")

    def close(self) -> None:
        """Close every connection and the listener; remove the socket file if it is ours."""
        for conn in list(self._connections.values()):
            self._drop(conn)
        if self._selector is not None:
            self._selector.close()
            self._selector = None
        if self._listener is not None:
            self._listener.close()
            self._listener = None
        if self._socket_file is not None and self.address.path is not None:
            with contextlib.suppress(FileNotFoundError):
                info = os.stat(self.address.path)
                if (info.st_dev, info.st_ino) == self._socket_file:
                    self.address.path.unlink()
            self._socket_file = None
        wake, self._wake = self._wake, None
        for sock in wake or ():
            sock.close()

    # ------------------------------------------------------------------ main loop
    def serve(self) -> list[EpisodeResult]:
        """Run until ``episodes`` episodes have ended or :meth:`stop`; returns the results."""
        if self._listener is None:
            self.open()
        while not self._stop.is_set() and not self._all_done():
            if self._episode is None:
                self._poll(IDLE_POLL_S)
            else:
                self._poll(0.0)
                if self._episode is not None and not self._stop.is_set():
                    self._step()
        if self._episode is not None:
            self._finish(P.ABORTED, "shutdown")
        return self.results

    def _all_done(self) -> bool:
        return self.episodes is not None and len(self.results) >= self.episodes

    def _poll(self, timeout: float) -> None:
        assert self._selector is not None
        for key, _ in self._selector.select(timeout):
            if key.data == "listen":
                self._accept()
            elif key.data == "wake":
                with contextlib.suppress(BlockingIOError):
                    key.fileobj.recv(64)
            else:
                self._read(key.data)

    def _accept(self) -> None:
        assert self._listener is not None and self._selector is not None
        try:
            sock, peer = self._listener.accept()
        except BlockingIOError:
            return
        sock.settimeout(self.send_timeout_s)  # recv only when readable; sends may wait this long
        conn = _Connection(sock, f"client{self._next_conn}@{peer or self.address}")
        self._next_conn += 1
        if len(self._connections) >= self.max_connections:
            self._send(
                conn, P.error_line("too_many_connections", P.ERROR_CODES["too_many_connections"])
            )
            sock.close()
            return
        self._connections[sock] = conn
        self._selector.register(sock, selectors.EVENT_READ, conn)
        logger.info("%s connected", conn.name)

    def _read(self, conn: _Connection) -> None:
        try:
            data = conn.sock.recv(4096)
        except OSError:
            data = b""
        if not data:
            self._drop(conn)
            return
        for raw in conn.lines.feed(data):
            if conn.sock not in self._connections:
                return  # dropped while answering an earlier line
            self._handle(conn, raw)

    def _handle(self, conn: _Connection, raw: bytes | None) -> None:
        if raw is None:
            self._send(conn, P.error_line("line_too_long", P.ERROR_CODES["line_too_long"]))
            return
        try:
            line = raw.decode("utf-8").strip()
        except UnicodeDecodeError as err:
            self._send(conn, P.error_line("bad_encoding", f"not UTF-8: {err}"))
            return
        if not line:
            self._send(conn, P.error_line("empty", "an empty line; send an instruction or 'done'"))
        elif P.is_done(line):
            self._done(conn)
        else:
            self._instruction(conn, line)

    def _done(self, conn: _Connection) -> None:
        episode = self._episode
        if episode is None:
            self._send(conn, P.error_line("not_running", "no episode is running", P.DONE))
            return
        episode.done_by.append(conn)
        self._finish(P.SUCCESS if episode.success else P.FAILURE, "done")

    def _instruction(self, conn: _Connection, instruction: str) -> None:
        if self._episode is not None:
            message = (
                f"episode {self._episode.index} ({self._episode.instruction!r}) is running; "
                "send 'done' first or wait for its result"
            )
            self._send(conn, P.error_line("busy", message, instruction))
            return
        index = self._next_index
        seed = None if self.seed is None else self.seed + index
        options = {"instruction": instruction} if self.env_instruction else None
        try:
            observation, _ = self.env.reset(seed=seed, options=options)
        except ValueError as err:  # e.g. Pick: "unknown instruction ...; one of (...)"
            self._send(conn, P.error_line("bad_instruction", str(err), instruction))
            return
        except Exception as err:
            logger.exception("env.reset failed")
            self._send(conn, P.error_line("internal", f"env.reset: {err!r}", instruction))
            return
        self.policy.reset()
        self._next_index += 1
        self._episode = _Episode(index, instruction, conn, observation)
        logger.info("episode %d: %r (from %s)", index, instruction, conn.name)
        self._send(conn, P.reply_line(P.STARTED, episode=index, instruction=instruction))

    def _step(self) -> None:
        episode = self._episode
        assert episode is not None
        try:
            action = self.policy.act(episode.observation, episode.instruction)
            observation, _, terminated, truncated, info = self.env.step(action)
        except Exception as err:
            logger.exception("episode %d: the policy or env raised", episode.index)
            self._finish(P.ERROR, "exception", message=f"{type(err).__name__}: {err}")
            return
        episode.observation = observation
        episode.steps += 1
        episode.success = bool(info.get("is_success", False))
        if terminated or truncated or episode.steps >= self.max_steps:
            reason = "max_steps" if not terminated else "terminated"
            if episode.success:
                reason = "success"
            self._finish(P.SUCCESS if episode.success else P.FAILURE, reason)

    def _finish(self, status: str, reason: str, message: str | None = None) -> None:
        episode = self._episode
        assert episode is not None
        self._episode = None
        result = EpisodeResult(
            episode.index, episode.instruction, status, reason, episode.steps, message
        )
        self.results.append(result)
        logger.info(
            "episode %d: %s (%s) after %d steps", result.episode, status, reason, result.steps
        )
        line = result.line()
        recipients = [episode.owner, *episode.done_by]
        for conn in dict.fromkeys(c for c in recipients if c is not None):
            if conn.sock in self._connections:
                self._send(conn, line)
        if self.on_result is not None:
            self.on_result(result)

    # ------------------------------------------------------------------ connections
    def _send(self, conn: _Connection, line: bytes) -> None:
        try:
            conn.sock.sendall(line)
        except OSError as err:  # gone, or not reading for send_timeout_s
            logger.warning("%s: dropped (%s)", conn.name, err)
            self._drop(conn)

    def _drop(self, conn: _Connection) -> None:
        if self._connections.pop(conn.sock, None) is not None and self._selector is not None:
            with contextlib.suppress(KeyError, ValueError):
                self._selector.unregister(conn.sock)
        with contextlib.suppress(OSError):
            conn.sock.close()
        if self._episode is not None and self._episode.owner is conn:
            self._episode.owner = None  # the episode goes on; 'done' from anyone ends it


@contextlib.contextmanager
def stop_on_signals(
    server: RolloutServer, signums: tuple[int, ...] = (signal.SIGINT, signal.SIGTERM)
) -> Iterator[list[int]]:
    """Within the block, the first SIGINT/SIGTERM stops ``server`` cleanly (a running episode
    is aborted, the socket file removed); a second one acts as it normally would. Yields the
    list of signals received. Main thread only (Python's signal rule)."""
    received: list[int] = []
    previous = {s: signal.getsignal(s) for s in signums}

    def handler(signum: int, frame: object) -> None:
        received.append(signum)
        for s, h in previous.items():
            signal.signal(s, h)
        server.stop()

    for s in signums:
        signal.signal(s, handler)
    try:
        yield received
    finally:
        for s, h in previous.items():
            signal.signal(s, h)
