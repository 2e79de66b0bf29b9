"""SIGTERM unwinding like Ctrl-C, for the CLIs that write through staging directories.

A ``kill`` then runs the same clean-up (staged outputs removed, nothing half-written) and
ends with the shell's exit status for that signal (130 for SIGINT, 143 for SIGTERM).
"""

from __future__ import annotations

import signal
from collections.abc import Iterator
from contextlib import contextmanager


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised where the process is, so that ``finally`` blocks and stagers run."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum


_received: list[int] = []  # the SIGTERMs seen inside the block (a library may re-raise the
# interrupt as a plain KeyboardInterrupt, e.g. Ray's ray.get)


def _raise_terminated(signum, frame) -> None:
    _received.append(signum)
    raise Terminated(signum)


@contextmanager
def sigterm_as_keyboard_interrupt() -> Iterator[None]:
    """Within the block SIGTERM raises :class:`Terminated`; the previous handler comes back."""
    _received.clear()
    previous = signal.signal(signal.SIGTERM, _raise_terminated)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def interrupted_signal(exc: KeyboardInterrupt) -> signal.Signals:
    """The signal behind an interrupt: SIGTERM for :class:`Terminated` (or when one arrived in
    the block), else SIGINT (Ctrl-C)."""
    return signal.Signals(getattr(exc, "signum", _received[-1] if _received else signal.SIGINT))
