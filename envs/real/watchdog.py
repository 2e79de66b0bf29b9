"""A watchdog that stops the arm when commands stop arriving.

RMB has none: its loop sends a ``servoJ`` / ``set_servo_angle`` every 20 ms, and if the Python
process hangs, the arm holds (UR) or finishes (xArm) its last target with nothing watching. Here
a command ``feed``\\ s the watchdog with the time it asked the arm to take; when no next command
arrives within ``timeout`` seconds after that time has run out, the watchdog trips: it calls
``on_trip`` (the safety layer's ``driver.stop()``) once, and stays tripped, so every later
command is refused, until :meth:`Watchdog.resume`.

Two things can notice an expired deadline, and whichever comes first trips it (exactly once):

- :meth:`Watchdog.poll`, which the safety layer calls at the start of every command, so a late
  command is refused even where no thread runs (and in tests, with an injected clock);
- a background thread, which sleeps on a condition variable until the deadline (no busy loop),
  started when the watchdog is first armed and joined by :meth:`Watchdog.close`.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Protocol


class Lock(Protocol):
    """What the watchdog needs of a lock (``threading.RLock`` has it)."""

    def acquire(self, blocking: bool = ..., timeout: float = ...) -> bool: ...

    def release(self) -> None: ...


class Watchdog:
    """Trips once when armed and not fed for ``timeout`` seconds.

    Args:
        timeout: Seconds without a command (after the last command's duration) that trip it.
        on_trip: Called once per trip (the layer stops the arm); its exceptions are kept in
            :attr:`trip_error`, never raised in the thread.
        clock: Monotonic clock in seconds (injectable for tests).
        thread: Run the background thread; ``False`` leaves tripping to :meth:`poll` alone.
        lock: A lock the thread takes before tripping, so that a trip never lands between a
            command's last check and its send (the layer's command lock, re-entrant).
        lock_wait: How long the thread waits for ``lock`` (s); when the holder is stuck longer
            (a hung driver call), it trips without it.
    """

    def __init__(
        self,
        timeout: float,
        on_trip: Callable[[], None],
        *,
        clock: Callable[[], float] = time.monotonic,
        thread: bool = True,
        lock: Lock | None = None,
        lock_wait: float | None = None,
    ):
        if not timeout > 0:
            raise ValueError(f"watchdog timeout must be > 0 s, got {timeout}")
        self.timeout = float(timeout)
        self._on_trip = on_trip
        self._clock = clock
        self._use_thread = thread
        self._lock = lock
        self._lock_wait = self.timeout if lock_wait is None else float(lock_wait)
        self._cond = threading.Condition()
        self._armed = False
        self._tripped = False
        self._closed = False
        self._deadline = 0.0
        self._thread: threading.Thread | None = None
        self.trip_count = 0
        self.trip_error: BaseException | None = None

    @property
    def armed(self) -> bool:
        """Whether the watchdog is watching."""
        return self._armed

    @property
    def tripped(self) -> bool:
        """Whether it tripped and has not been resumed."""
        return self._tripped

    def arm(self) -> None:
        """Start watching: the next command must arrive within ``timeout`` from now."""
        with self._cond:
            if self._closed:
                raise RuntimeError("the watchdog is closed")
            self._armed = True
            self._deadline = self._clock() + self.timeout
            if self._use_thread and self._thread is None:
                self._thread = threading.Thread(
                    target=self._run, name="rmb-safety-watchdog", daemon=True
                )
                self._thread.start()
            self._cond.notify_all()

    def disarm(self) -> None:
        """Stop watching (a planned pause: between episodes, while saving)."""
        with self._cond:
            self._armed = False
            self._cond.notify_all()

    def resume(self) -> None:
        """Clear a trip and arm again."""
        with self._cond:
            self._tripped = False
        self.arm()

    def feed(self, hold: float = 0.0) -> None:
        """A command went out: the next is due ``hold + timeout`` seconds from now.

        Args:
            hold: The duration the command gave the arm (s).
        """
        with self._cond:
            self._deadline = self._clock() + max(float(hold), 0.0) + self.timeout
            self._cond.notify_all()

    def poll(self) -> bool:
        """Trip now if armed and past the deadline.

        Returns:
            Whether the watchdog is tripped (now or before).
        """
        with self._cond:
            if self._tripped:
                return True
            if not self._expired():
                return False
            self._tripped = True
        self._fire()
        return True

    def close(self) -> None:
        """Stop the thread (joined); safe to call twice."""
        with self._cond:
            self._closed = True
            self._armed = False
            self._cond.notify_all()
        thread, self._thread = self._thread, None
        if thread is not None and thread is not threading.current_thread():
            thread.join(timeout=max(5.0, 2 * self._lock_wait))

    def _expired(self) -> bool:
        return self._armed and not self._closed and self._clock() > self._deadline

    def _fire(self) -> None:
        self.trip_count += 1
        try:
            self._on_trip()
        except Exception as exc:  # the thread must survive; the layer reports it
            self.trip_error = exc

    def _run(self) -> None:
        while True:
            with self._cond:
                while not self._closed and not (self._armed and not self._tripped):
                    self._cond.wait()
                if self._closed:
                    return
                remaining = self._deadline - self._clock()
                if remaining > 0:
                    self._cond.wait(timeout=remaining)
                    continue
            self._trip_from_thread()

    def _trip_from_thread(self) -> None:
        lock = self._lock
        got = lock.acquire(timeout=self._lock_wait) if lock is not None else False
        try:
            with self._cond:
                # Re-check: a command may have fed it meanwhile. Only when the lock's holder is
                # stuck (not got) does the expired deadline seen before stand unchecked.
                recheck = got or lock is None
                if self._tripped or not self._armed or (recheck and not self._expired()):
                    return
                self._tripped = True
            self._fire()
        finally:
            if got and lock is not None:
                lock.release()
