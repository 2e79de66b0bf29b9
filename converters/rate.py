"""Frame rates of converted datasets: measured from RMB's ``time`` key, kept exact.

RMB's MuJoCo UR5e envs step at 31.25 Hz (0.004 s x 8). LeRobot types ``fps`` as ``int``, but
what it does with it works for any rational rate once the video encoder gets an exact fraction:
timestamps are ``frame_index / fps``, ``delta_timestamps`` are checked against ``1 / fps``, and
frames are found by timestamp. What fails is only its video writer handing a ``float`` to PyAV
(``add_stream``/``Fraction(1, fps)`` need a rational). So a dataset keeps the true rate (31.25 in
``info.json``, an ``int`` when the rate is whole) and :mod:`.encoder` encodes with
``Fraction(125, 4)``: every frame's timestamp is exact, nothing is resampled or stretched.

A dataset's frames are evenly spaced by definition, so a ``time`` key is only trusted when it
is regular and plausible: :func:`rmb_lerobot.episode.timing.control_rate` (one check for the
reader and the converter) refuses gaps, values that do not increase, NaN/inf and rates no
robot records at (e.g. ``time`` in milliseconds). ``--fps`` overrides it: the user asserts the
rate, and what ``control_rate`` found becomes a warning (:mod:`.plan`).
"""

from __future__ import annotations

from fractions import Fraction

# Nominal rates are simple fractions: 31.25 = 125/4, 15.625 = 125/8 (31.25 with --skip 2), 30.
NICE_DENOMINATOR = 8
# A measured mean rate this close (relative) to a simple fraction is that fraction; a real
# robot's clock jitters, so its episodes' mean rates differ slightly.
RATE_TOLERANCE = 0.005


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
