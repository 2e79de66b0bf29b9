"""Real-time scheduling for the control loop's thread (Linux ``SCHED_FIFO``).

A sleep-and-spin loop cannot beat the scheduler: on a busy machine the loop's thread waits
behind other runnable threads for whole scheduler ticks (measured here: period error p99 ~10 ms
at 50 Hz with other work running, ~0.5 ms for the same loop under ``SCHED_FIFO``; RESULTS.md
"Real control loop"). ur-rtde runs its own threads at a real-time priority for the same reason
(its ``rt_priority``). Asking for it is a choice of the lab's: it needs ``CAP_SYS_NICE`` or an
``rtprio`` limit (``ulimit -r``, or ``@realtime - rtprio 99`` in ``/etc/security/limits.conf``),
and the kernel's real-time throttling (``/proc/sys/kernel/sched_rt_runtime_us``, 95 % by
default) keeps a spinning FIFO thread from locking the machine up.
"""

from __future__ import annotations

import contextlib
import os
import sys
import threading
from dataclasses import dataclass

MIN_PRIORITY = 1
MAX_PRIORITY = 99


@dataclass(frozen=True)
class PreviousPolicy:
    """A thread's scheduling policy before :func:`use_realtime_priority` changed it."""

    thread_id: int
    policy: int
    priority: int

    def restore(self) -> None:
        """Put the thread back on its previous policy (a no-op once the thread has ended)."""
        with contextlib.suppress(ProcessLookupError):
            os.sched_setscheduler(self.thread_id, self.policy, os.sched_param(self.priority))


def use_realtime_priority(priority: int) -> PreviousPolicy:
    """Run the calling thread under ``SCHED_FIFO`` at ``priority``.

    Args:
        priority: 1 (lowest) to 99; ur-rtde's default for its own threads is 80, so a loop
            that feeds it sits just below (e.g. 70) or at the same level.

    Returns:
        The previous policy, to :meth:`PreviousPolicy.restore` when the loop ends.

    Raises:
        ValueError: ``priority`` outside 1..99.
        OSError: Not Linux (no ``SCHED_FIFO`` here), or the process may not raise its priority
            (the message says how to allow it).
    """
    if not MIN_PRIORITY <= priority <= MAX_PRIORITY:
        raise ValueError(
            f"realtime_priority must be in {MIN_PRIORITY}..{MAX_PRIORITY}, got {priority}"
        )
    if not sys.platform.startswith("linux"):
        raise OSError(f"realtime_priority needs Linux's SCHED_FIFO; this is {sys.platform}")
    thread_id = threading.get_native_id()
    previous = PreviousPolicy(
        thread_id,
        os.sched_getscheduler(thread_id),
        os.sched_getparam(thread_id).sched_priority,
    )
    try:
        os.sched_setscheduler(thread_id, os.SCHED_FIFO, os.sched_param(priority))
    except PermissionError as exc:
        raise PermissionError(
            f"realtime_priority {priority}: this process may not use SCHED_FIFO. Allow it "
            "with `ulimit -r 99` in the shell that starts it (after adding "
            "'@realtime - rtprio 99' for your user's group in /etc/security/limits.conf), or "
            "grant CAP_SYS_NICE (`sudo setcap cap_sys_nice+ep $(readlink -f $(which python))`)"
            "; or leave realtime_priority unset"
        ) from exc
    return previous
