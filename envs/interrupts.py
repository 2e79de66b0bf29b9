"""SIGINT and SIGTERM as an exception that never lands inside an episode's bookkeeping.

Python runs a signal handler in the main thread between two bytecodes, wherever that is: inside
the writer's own clean-up, or inside a ``__del__`` or callback that swallows the exception (the
signal would be lost). So while an episode is being recorded (:func:`recording`) a signal is
only noted, and :func:`raise_if_signalled` raises it at the next safe point, between two steps
or right after the episode is complete; elsewhere it raises at once.

The parent process (``rmb-collect``) raises :class:`Interrupted`, inside
:func:`interrupts_raise`. Its worker processes install no handler (see
:mod:`rmb_lerobot.envs.collect`: a handler whose exception is lost leaves a worker that cannot
be stopped); the parent stops them through a shared flag.
"""

from __future__ import annotations

import contextlib
import signal
from collections.abc import Callable, Iterator

INTERRUPT_SIGNALS = (signal.SIGINT, signal.SIGTERM)

_recording = False  # inside recording(): signals wait for the next safe point
_pending: int | None = None  # a signal noted while recording, not yet raised


class Interrupted(BaseException):
    """SIGINT or SIGTERM arrived (see :func:`interrupts_raise`).

    A BaseException, like KeyboardInterrupt, so that no ``except Exception`` swallows it.
    """

    def __init__(self, signum: int):
        super().__init__(f"interrupted by {signal.Signals(signum).name}")
        self.signum = signum

    @property
    def exit_code(self) -> int:
        """The shell's convention for death by a signal: 130 for SIGINT, 143 for SIGTERM."""
        return 128 + self.signum


@contextlib.contextmanager
def recording() -> Iterator[None]:
    """Defer signals to :func:`raise_if_signalled` calls; raise a deferred one on leaving."""
    global _recording
    outer, _recording = _recording, True
    try:
        yield
    finally:
        _recording = outer
    raise_if_signalled()  # normal exit only: what was recorded is complete


def raise_if_signalled() -> None:
    """A safe point: raise :class:`Interrupted` for a signal noted while recording."""
    if _pending is not None:
        raise Interrupted(_pending)


def _note_or_raise(signum: int, exc: BaseException) -> None:
    global _pending
    if _recording:
        _pending = signum
        return
    raise exc


@contextlib.contextmanager
def interrupts_raise(on_repeat: Callable[[int], None] | None = None) -> Iterator[None]:
    """Within the block the first SIGINT or SIGTERM raises :class:`Interrupted` (main thread).

    Later ones must not cut short the clean-up that the first one started: they call
    ``on_repeat(signum)`` (e.g. to exit at once) or are ignored.
    """
    global _pending
    received: list[int] = []

    def handler(signum: int, frame: object) -> None:
        received.append(signum)
        if len(received) == 1:
            _note_or_raise(signum, Interrupted(signum))
        elif on_repeat is not None:
            on_repeat(signum)

    previous = {sig: signal.signal(sig, handler) for sig in INTERRUPT_SIGNALS}
    try:
        yield
    finally:
        for sig, old in previous.items():
            signal.signal(sig, old)
        _pending = None
