"""Frame rates of converted datasets: measured from RMB's ``time`` key, kept exact.

RMB's MuJoCo UR5e envs step at 31.25 Hz (0.004 s x 8). LeRobot types ``fps`` as ``int``, but
what it does with it works for any rational rate once the video encoder gets an exact fraction:
timestamps are ``frame_index / fps``, ``delta_timestamps`` are checked against ``1 / fps``, and
frames are found by timestamp. What fails is only its video writer handing a ``float`` to PyAV
(``add_stream``/``Fraction(1, fps)`` need a rational). So a dataset keeps the true rate (31.25 in
``info.json``, an ``int`` when the rate is whole) and :mod:`.encoder` encodes with
``Fraction(125, 4)``: every frame's timestamp is exact, nothing is resampled or stretched.

A dataset's frames are evenly spaced by definition, so a ``time`` key is only trusted when it
is: :func:`control_rate` refuses gaps and stalls (a step more than 50 % off the median step),
values that do not increase, NaN/inf, and rates no robot records at (outside 1..1000 Hz, e.g.
``time`` in milliseconds). ``--fps`` overrides it: the user asserts the rate, and what
:func:`control_rate` found becomes a warning.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np

from rmb_lerobot import keys as K
from rmb_lerobot.errors import RmbFormatError

# Nominal rates are simple fractions: 31.25 = 125/4, 15.625 = 125/8 (31.25 with --skip 2), 30.
NICE_DENOMINATOR = 8
# A measured mean rate this close (relative) to a simple fraction is that fraction; a real
# robot's clock jitters, so its episodes' mean rates differ slightly.
RATE_TOLERANCE = 0.005
# A step may differ this much (relative) from the episode's median step; more is a gap or stall.
STEP_TOLERANCE = 0.5
# Control rates a recorded robot episode can plausibly have, in Hz.
MIN_RATE_HZ = 1.0
MAX_RATE_HZ = 1000.0


def measured_rate(time: np.ndarray) -> float:
    """Mean steps per second of a ``time`` sequence (what RMB's ``time`` key holds).

    No regularity check: use :func:`control_rate` to decide a dataset's rate.
    """
    t = np.asarray(time, dtype=np.float64).reshape(-1)
    if t.size < 2 or not np.all(np.diff(t) > 0):
        raise ValueError("'time' must hold at least two increasing values")
    return float((t.size - 1) / (t[-1] - t[0]))


def control_rate(time: np.ndarray, *, path=None) -> float:
    """Steps per second of an episode's ``time`` key, if it is regular and plausible.

    Raises :class:`RmbFormatError` (naming ``path``, the key, the step and the values) when the
    steps are not evenly spaced within :data:`STEP_TOLERANCE` of their median, when ``time``
    holds NaN/inf or does not increase, or when the rate is outside
    ``MIN_RATE_HZ..MAX_RATE_HZ``. Returns the mean rate over the whole episode (jitter averages
    out); :func:`nominal_rate` turns it into the exact rate.
    """
    t = np.asarray(time, dtype=np.float64).reshape(-1)

    def fail(message: str) -> RmbFormatError:
        return RmbFormatError(f"'{K.TIME}' {message}", path=path, key=K.TIME)

    if t.size < 2:
        raise fail(f"needs at least two steps to give a frame rate, has {t.size}")
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        raise fail(f"holds {t[bad[0]]} at step {bad[0]} ({bad.size} non-finite values)")
    steps = np.diff(t)
    bad = np.flatnonzero(steps <= 0)
    if bad.size:
        i = int(bad[0])
        raise fail(
            f"does not increase at step {i + 1}: {t[i]!r} -> {t[i + 1]!r} "
            f"({bad.size} such steps); expected increasing seconds"
        )
    median = float(np.median(steps))
    off = np.flatnonzero(np.abs(steps - median) > STEP_TOLERANCE * median)
    if off.size:
        i = int(off[np.argmax(np.abs(steps[off] - median))])
        raise fail(
            f"is not evenly spaced: step {i} -> {i + 1} takes {steps[i]:.6g} s, the median step "
            f"{median:.6g} s ({off.size} steps more than {STEP_TOLERANCE:.0%} off: gaps, stalls "
            "or dropped frames); a dataset's frames are evenly spaced, so fix the episode or "
            "pass --fps RATE to assert its rate"
        )
    rate = float((t.size - 1) / (t[-1] - t[0]))
    if not MIN_RATE_HZ <= rate <= MAX_RATE_HZ:
        hint = ""
        if MIN_RATE_HZ <= rate * 1000 <= MAX_RATE_HZ:
            hint = f"; if 'time' is in milliseconds the rate is {rate * 1000:.6g} Hz"
        raise fail(
            f"gives {rate:.6g} Hz (median step {median:.6g}), outside the plausible "
            f"{MIN_RATE_HZ:g}..{MAX_RATE_HZ:g} Hz for seconds{hint}; pass --fps RATE to assert it"
        )
    return rate


def nominal_rate(rate: float | str | Fraction) -> Fraction:
    """The rate a measured or given one stands for, as an exact fraction (31.2499... -> 125/4).

    Strings are parsed exactly (``"31.25"``, ``"125/4"``). A rate near no simple fraction is
    kept to a thousandth of a Hz.
    """
    exact = Fraction(rate) if isinstance(rate, str | Fraction) else Fraction(float(rate))
    if exact <= 0:
        raise ValueError(f"frame rate must be positive, got {rate}")
    nice = exact.limit_denominator(NICE_DENOMINATOR)
    if abs(nice - exact) <= RATE_TOLERANCE * exact:
        return nice
    return exact.limit_denominator(1000)


def same_rate(a: float, b: float) -> bool:
    """Whether two measured rates are one rate (up to clock jitter)."""
    return abs(a - b) <= RATE_TOLERANCE * max(a, b)


def lerobot_fps(rate: Fraction) -> int | float:
    """The value written to ``info.json``: an int when whole, else the exact float (31.25)."""
    return int(rate) if rate.denominator == 1 else float(rate)


def exact_rate(fps: float | int | Fraction) -> Fraction:
    """Inverse of :func:`lerobot_fps` for the encoder: 31.25 -> Fraction(125, 4)."""
    return Fraction(fps).limit_denominator(1000)
