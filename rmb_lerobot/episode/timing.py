"""The control rate of an episode, from its ``time`` key, checked for regularity and plausibility.

RMB stores no frame rate anywhere but in ``time`` (its MP4s carry none), so everything that
needs one (``Episode.fps``, the LeRobot converter) takes it from here, in one place.

Why these limits:

- A step may last at most :data:`MAX_STEP_RATIO` (3) times the median step. RMB's simulated
  envs step exactly (31.25 Hz: 0.004 s x 8); its real envs run a 50 Hz loop whose steps
  stretch when a camera frame or the robot is late (RealSense at 30 fps, ``time`` is wall
  clock), so a real step of 1.5 to 2 times the median is ordinary and must pass. A step of 3
  or more periods is a gap: recording paused, steps dropped, episodes concatenated (a 0.3 s
  gap in a 31.25 Hz episode is 9.4 periods). Short steps are not limited (only ``dt > 0``):
  wall-clock stamps taken after a variable camera wait make a step after a late one short.
- The rate must lie in [:data:`MIN_RATE_HZ`, :data:`MAX_RATE_HZ`] = [1, 1000] Hz: manipulation
  control runs at 10 to 500 Hz; ``time`` in milliseconds reads as 0.03125 Hz, in
  microseconds as 3e-5 Hz, and is refused instead of becoming a 32-minute "step".

The rate returned is the mean over the episode, (steps - 1) / duration: for a jittery real
clock it is the effective rate, which the median would misstate.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rmb_lerobot import keys as K
from rmb_lerobot.errors import RmbFormatError

MAX_STEP_RATIO = 3.0
MIN_RATE_HZ = 1.0
MAX_RATE_HZ = 1000.0


def control_rate(
    time: np.ndarray,
    *,
    path: str | Path | None = None,
    key: str = K.TIME,
    max_step_ratio: float = MAX_STEP_RATIO,
) -> float:
    """Mean steps per second of a ``time`` sequence (seconds), after checking that it is regular.

    Raises :class:`RmbFormatError` (naming ``path`` and ``key``) unless ``time`` holds at least
    two finite, strictly increasing values whose every step lasts at most ``max_step_ratio``
    times the median step, at a rate in [1, 1000] Hz.
    """
    t = np.asarray(time, dtype=np.float64).reshape(-1)
    if t.size < 2:
        raise RmbFormatError(
            f"'time' holds {t.size} value(s); expected at least two to measure the control rate",
            path=path,
            key=key,
        )
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        raise RmbFormatError(
            f"'time' holds {t[bad[0]]} at step {int(bad[0])}; expected finite seconds",
            path=path,
            key=key,
        )
    dt = np.diff(t)
    back = np.flatnonzero(dt <= 0)
    if back.size:
        i = int(back[0]) + 1
        raise RmbFormatError(
            f"'time' does not increase at step {i} ({t[i - 1]:.6g} s -> {t[i]:.6g} s"
            f"{f', and {back.size - 1} more steps' if back.size > 1 else ''}); expected "
            "strictly increasing seconds",
            path=path,
            key=key,
        )
    median = float(np.median(dt))
    rate = float((t.size - 1) / (t[-1] - t[0]))
    if not MIN_RATE_HZ <= rate <= MAX_RATE_HZ:
        hint = " ('time' in milliseconds?)" if rate < MIN_RATE_HZ else ""
        raise RmbFormatError(
            f"'time' gives a control rate of {rate:.6g} Hz (median step {median:.6g} s){hint}; "
            f"expected seconds at {MIN_RATE_HZ:g} to {MAX_RATE_HZ:g} Hz",
            path=path,
            key=key,
        )
    long = np.flatnonzero(dt > max_step_ratio * median)
    if long.size:
        i = int(long[0]) + 1
        more = f" (and {long.size - 1} more such steps)" if long.size > 1 else ""
        raise RmbFormatError(
            f"'time' jumps by {dt[i - 1]:.6g} s at step {i}{more}, {dt[i - 1] / median:.3g} times "
            f"the median step of {median:.6g} s ({1 / median:.6g} Hz); expected regular steps, "
            f"each at most {max_step_ratio:g} times the median (a gap in the recording?)",
            path=path,
            key=key,
        )
    return rate
