"""A background thread that runs an episode's image encoders while the caller steps on.

Encoding a 640x480 frame costs milliseconds (libx264 for RGB, the lossless depth video), and
a recording loop (``rmb-teleop``, ``rmb-collect``) would otherwise pay it on every step before
it can render and step the next one. PyAV releases the GIL while the encoder and the pixel
format conversion run (``avcodec_send_frame`` and ``sws_scale`` are called ``with nogil``), and
MuJoCo releases it in ``mj_step`` and its renderer, so the encoding overlaps the loop on
another core.

One thread runs every job in submission order, so each encoder sees its frames in the same
order as a synchronous writer would give them, and the files are byte-identical. The queue is
bounded: a caller faster than the encoder waits (back-pressure) instead of buffering frames
without limit. The first exception of a job is kept and re-raised to the caller at its next
:meth:`EncodeWorker.submit` or :meth:`EncodeWorker.finish` (and every one after); later jobs
are skipped.
"""

from __future__ import annotations

import queue
import threading
from collections.abc import Callable
from typing import Any

DEFAULT_QUEUE_SIZE = 16
"""Jobs (one image each) waiting at most: 16 x 640x480 float32 depth is about 20 MB."""

_STOP = None  # the sentinel that ends the thread


class EncodeWorker:
    """Run ``fn(*args)`` jobs in order on one daemon thread; errors surface in the caller.

    Args:
        max_queued: Jobs that may wait before :meth:`submit` blocks (at least 1).
        name: The thread's name (shown by debuggers and ``threading.enumerate``).
    """

    def __init__(self, max_queued: int = DEFAULT_QUEUE_SIZE, name: str = "rmb-encode"):
        if max_queued < 1:
            raise ValueError(f"max_queued must be at least 1, got {max_queued}")
        self._queue: queue.Queue[tuple[Callable[..., Any], tuple[Any, ...]] | None] = queue.Queue(
            maxsize=max_queued
        )
        self._error: BaseException | None = None
        self._cancelled = False
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while True:
            job = self._queue.get()
            if job is _STOP:
                return
            if self._error is not None or self._cancelled:
                continue  # drain, so a blocked submit() or finish() goes on
            fn, args = job
            try:
                fn(*args)
            except BaseException as error:  # re-raised in the caller's thread
                self._error = error

    def raise_pending(self) -> None:
        """Re-raise a failed job's exception in the caller's thread.

        Sticky: every later call raises it again (a caller that caught it and went on to
        ``finish`` must not take the file for complete); only :meth:`cancel` clears it.
        """
        if self._error is not None:
            self._cancelled = True  # the jobs after a failed one would write a broken file
            raise self._error

    def submit(self, fn: Callable[..., Any], *args: Any) -> None:
        """Queue ``fn(*args)``; blocks while the queue is full.

        Raises:
            RuntimeError: The worker was finished or cancelled.
            BaseException: The exception of an earlier job.
        """
        self.raise_pending()
        if self._cancelled or not self._thread.is_alive():
            raise RuntimeError("the encode worker is stopped; expected no more jobs")
        self._queue.put((fn, args))

    def finish(self) -> None:
        """Wait until every queued job has run, then stop the thread.

        Raises:
            BaseException: The exception of a job that failed.
        """
        self._stop()
        self.raise_pending()

    def cancel(self) -> None:
        """Skip the queued jobs and stop the thread (a discarded episode); never raises."""
        self._cancelled = True
        self._stop()
        self._error = None

    def _stop(self) -> None:
        if self._thread.is_alive():
            self._queue.put(_STOP)
            self._thread.join()
