"""Key sources for teleoperation: a terminal, a window (pynput), a script.

Every source implements :class:`~rmb_lerobot.envs.teleop.device.KeySource`: ``poll()`` returns
the keys pressed since the last call, oldest first, as lower-case characters or names
(:data:`KEY_NAMES`). The teleop loop polls one source once per control step and routes the keys
(phase keys to the phase machine, the rest to a keyboard device), so one reader feeds both.

- :class:`TerminalKeySource` reads a TTY in cbreak mode (no line buffering, no echo; Ctrl-C
  still sends SIGINT): it needs no display, so it works over SSH, in a container and, on a
  pseudo-terminal, in tests. The terminal's settings are restored on :meth:`close`, on leaving a
  ``with`` block (exception or not) and at interpreter exit.
- :class:`PynputKeySource` listens to a desktop session through pynput (LeRobot's ``pynput-dep``
  extra; imported lazily), as RMB's keyboard device does.
- :class:`ScriptedKeySource` replays ``(step, key)`` events: tests and demos.

A terminal reports key *presses* (held keys repeat at the terminal's auto-repeat rate, about
30 Hz after a 0.5 s delay), never releases, so one press moves the robot one step.
"""

from __future__ import annotations

import atexit
import contextlib
import os
import queue
import select
import sys
import termios
import tty
from collections.abc import Iterable, Sequence
from typing import Any

from rmb_lerobot.display import has_display

ESC = "\x1b"
# Escape sequences of the keys we name (xterm and VT100 cursor keys, both modes).
ESCAPE_SEQUENCES = {
    "\x1b[A": "up",
    "\x1b[B": "down",
    "\x1b[C": "right",
    "\x1b[D": "left",
    "\x1bOA": "up",
    "\x1bOB": "down",
    "\x1bOC": "right",
    "\x1bOD": "left",
    "\x1b[H": "home",
    "\x1b[F": "end",
    "\x1b[3~": "delete",
}
CONTROL_CHARS = {"\t": "tab", " ": "space", "\r": "enter", "\n": "enter", "\x7f": "backspace"}
KEY_NAMES = ("esc", "tab", "space", "enter", "backspace", "up", "down", "left", "right")
"""Names of non-character keys that every source reports the same way."""

# How long a lone ESC waits for the rest of an escape sequence (the terminal sends a sequence in
# one write; over SSH its bytes may arrive a few milliseconds apart).
ESCAPE_WAIT_S = 0.02


def parse_keys(text: str) -> tuple[list[str], str]:
    r"""Split terminal input into key names.

    Args:
        text: Characters read from a terminal in cbreak mode.

    Returns:
        The keys, and a trailing incomplete escape sequence (``"\x1b"``, ``"\x1b["``) to
        prepend to the next read.
    """
    keys: list[str] = []
    i = 0
    while i < len(text):
        char = text[i]
        if char == ESC:
            rest = text[i:]
            match = next((seq for seq in ESCAPE_SEQUENCES if rest.startswith(seq)), None)
            if match is not None:
                keys.append(ESCAPE_SEQUENCES[match])
                i += len(match)
                continue
            if any(seq.startswith(rest) for seq in ESCAPE_SEQUENCES):
                return keys, rest  # a sequence cut short: wait for its end
            if len(rest) >= 2 and rest[1] in "[O":
                # An unknown CSI/SS3 sequence (F-keys, modifiers): skip to its final byte.
                j = i + 2
                while j < len(text) and not ("@" <= text[j] <= "~"):
                    j += 1
                i = j + 1
                continue
            keys.append("esc")
            i += 1
            continue
        if char in CONTROL_CHARS:
            keys.append(CONTROL_CHARS[char])
        elif char.isprintable():
            keys.append(char.lower())
        i += 1
    return keys, ""


class TerminalKeySource:
    """Key presses from a terminal in cbreak mode (no display needed).

    Args:
        fd: The terminal's file descriptor; default: standard input if it is a terminal, else
            ``/dev/tty`` (the controlling terminal, opened here and closed by :meth:`close`).

    Raises:
        OSError: There is no terminal (``fd`` is not one, or the process has none).
    """

    def __init__(self, fd: int | None = None):
        self._own_fd = False
        if fd is None:
            if sys.stdin is not None and sys.stdin.isatty():
                fd = sys.stdin.fileno()
            else:
                fd = os.open("/dev/tty", os.O_RDONLY | os.O_NOCTTY)
                self._own_fd = True
        if not os.isatty(fd):
            raise OSError(f"file descriptor {fd} is not a terminal; keys cannot be read from it")
        self.fd = fd
        self._saved: list[Any] | None = termios.tcgetattr(fd)
        self._pending = ""
        tty.setcbreak(fd, termios.TCSANOW)  # keeps ISIG: Ctrl-C still raises SIGINT
        atexit.register(self.close)

    def _read_available(self, timeout: float) -> str:
        chunks = []
        while select.select([self.fd], [], [], timeout)[0]:
            data = os.read(self.fd, 1024)
            if not data:
                break
            chunks.append(data.decode("utf-8", errors="ignore"))
            timeout = 0.0
        return "".join(chunks)

    def poll(self) -> list[str]:
        """Return the keys pressed since the last call, oldest first (never blocks long)."""
        if self._saved is None:
            return []
        text = self._pending + self._read_available(0.0)
        keys, pending = parse_keys(text)
        if pending:
            # A lone ESC, or a sequence whose end has not arrived yet: wait for it briefly.
            more = self._read_available(ESCAPE_WAIT_S)
            if more:
                rest, pending = parse_keys(pending + more)
                keys += rest
            if pending:  # still cut short: the ESC key itself, then what followed it
                keys.append("esc")
                keys += parse_keys(pending[1:])[0]
                pending = ""
        self._pending = pending
        return keys

    def close(self) -> None:
        """Restore the terminal's settings; safe to call twice."""
        saved, self._saved = self._saved, None
        if saved is not None:
            with contextlib.suppress(termios.error, OSError):
                termios.tcsetattr(self.fd, termios.TCSADRAIN, saved)
            if self._own_fd:
                with contextlib.suppress(OSError):
                    os.close(self.fd)
        atexit.unregister(self.close)

    def __enter__(self) -> TerminalKeySource:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class PynputKeySource:
    """Key presses from the desktop session (X11, Wayland with XWayland, macOS, Windows).

    Raises:
        ImportError: pynput is not installed (``pip install pynput``, or LeRobot's
            ``pynput-dep`` extra).
    """

    def __init__(self) -> None:
        try:
            from pynput import keyboard
        except ImportError as exc:
            raise ImportError(
                "the pynput key source needs pynput: pip install pynput (LeRobot's extra "
                "lerobot[pynput-dep]); without a display use the terminal key source (--keys "
                "terminal)"
            ) from exc
        self._keyboard = keyboard
        self._queue: queue.SimpleQueue[str] = queue.SimpleQueue()
        self._listener = keyboard.Listener(on_press=self._on_press)
        self._listener.start()

    def _on_press(self, key: Any) -> None:
        name = self.key_name(key)
        if name is not None:
            self._queue.put(name)

    def key_name(self, key: Any) -> str | None:
        """The name of a pynput key (a character, or one of :data:`KEY_NAMES`), or None."""
        char = getattr(key, "char", None)
        if char is not None:
            return CONTROL_CHARS.get(char, char.lower())
        name = getattr(key, "name", None)
        return name if name in KEY_NAMES else None

    def poll(self) -> list[str]:
        """Return the keys pressed since the last call, oldest first."""
        keys = []
        while True:
            try:
                keys.append(self._queue.get_nowait())
            except queue.Empty:
                return keys

    def close(self) -> None:
        """Stop the listener thread; safe to call twice."""
        self._listener.stop()


class ScriptedKeySource:
    """Keys from a script of ``(step, key)`` events: poll number ``step`` (0-based) returns them.

    Args:
        events: ``(step, key)`` pairs, in any order; several keys may share a step.
        then: Keys returned by the first poll after the last event (default ``("esc",)``, so a
            scripted session ends instead of waiting for ever); ``()`` for none.
    """

    def __init__(self, events: Iterable[tuple[int, str]], then: Sequence[str] = ("esc",)):
        self.events = sorted(events, key=lambda event: event[0])
        self.then = tuple(then)
        self.polls = 0
        self._last = self.events[-1][0] if self.events else -1

    def poll(self) -> list[str]:
        """Return this poll's scripted keys."""
        step, self.polls = self.polls, self.polls + 1
        keys = [key for at, key in self.events if at == step]
        if step == self._last + 1:
            keys += self.then
        return keys

    def close(self) -> None:
        """Nothing to release."""


class NoKeySource:
    """No keys ever (a headless run that needs none, e.g. ``--auto-replay``)."""

    def poll(self) -> list[str]:
        """Return no keys."""
        return []

    def close(self) -> None:
        """Nothing to release."""


def stdin_is_terminal() -> bool:
    """Whether standard input is a terminal (the terminal source's default)."""
    return sys.stdin is not None and sys.stdin.isatty()


KEY_SOURCES = ("auto", "terminal", "pynput", "none")


def make_key_source(kind: str = "auto") -> TerminalKeySource | PynputKeySource | NoKeySource:
    """The key source ``kind`` names.

    ``auto`` takes the terminal when standard input is one (over SSH too; keys reach it only
    while its window has focus), else pynput where a display exists and pynput is installed.

    Args:
        kind: One of :data:`KEY_SOURCES`.

    Returns:
        The key source (close it when done).

    Raises:
        ValueError: An unknown kind, or ``auto`` with neither a terminal nor a display.
        ImportError: ``pynput`` without pynput installed.
        OSError: ``terminal`` without a terminal.
    """
    if kind not in KEY_SOURCES:
        raise ValueError(f"key source must be one of {', '.join(KEY_SOURCES)}, got {kind!r}")
    if kind == "none":
        return NoKeySource()
    if kind == "terminal" or (kind == "auto" and stdin_is_terminal()):
        return TerminalKeySource()
    if kind == "pynput":
        return PynputKeySource()
    if has_display():
        with contextlib.suppress(ImportError):
            return PynputKeySource()
    raise ValueError(
        "no key source: standard input is not a terminal and there is no display with pynput; "
        "run rmb-teleop in a terminal (over SSH works), or install pynput on a desktop"
    )
