"""What every teleoperator of this package shares: LeRobot's abstract methods that none of them
needs (no feedback, nothing to calibrate or configure), action features from a key list, and
a check of the rate the loop polls it at."""

from __future__ import annotations

import logging
import statistics
import time
from collections.abc import Callable
from typing import Any

from lerobot.teleoperators.teleoperator import Teleoperator

log = logging.getLogger(__name__)


class KeyedTeleoperator(Teleoperator):
    """A LeRobot teleoperator that emits a fixed list of ``float`` action keys (``_keys``, set
    by the subclass) and takes no feedback.

    Subclasses implement ``is_connected``, ``connect``, ``get_action`` and ``disconnect``.
    """

    _keys: tuple[str, ...]

    @property
    def action_features(self) -> dict[str, type]:
        """Every action key this teleoperator emits, as ``float``."""
        return dict.fromkeys(self._keys, float)

    @property
    def feedback_features(self) -> dict[str, type]:
        """None: no feedback is taken."""
        return {}

    @property
    def is_calibrated(self) -> bool:
        """Always: what calibration there is comes from the config."""
        return True

    def calibrate(self) -> None:
        """Nothing to calibrate."""

    def configure(self) -> None:
        """Nothing to configure."""

    def send_feedback(self, feedback: dict[str, Any]) -> None:
        """Ignored: no force or state feedback.

        Args:
            feedback: Anything.
        """


class RateCheck:
    """Warn once when a teleoperator is polled at another rate than it assumes.

    LeRobot's loops pass a teleoperator neither ``--fps`` nor the robot's
    ``command_duration_s``, yet a velocity teleoperator's twist is its step divided by the
    period it assumes: polled slower or faster, the robot moves less or more than RMB's step
    per action. The period between ``get_action`` calls is what the code can see, so it is
    measured: after each ``window`` calls, the median period (robust to the pause while
    ``lerobot-record`` saves an episode) is compared with the assumed one.

    Args:
        who: The teleoperator's name, for the message.
        period_s: The period it assumes (s).
        hint: What to set so the two agree (named in the message).
        window: Calls per check.
        tolerance: Relative difference that is warned about.
        clock: Seconds, monotonic (injectable for tests).
    """

    def __init__(
        self,
        who: str,
        period_s: float,
        hint: str,
        *,
        window: int = 30,
        tolerance: float = 0.25,
        clock: Callable[[], float] = time.monotonic,
    ):
        self.who, self.period_s, self.hint = who, float(period_s), hint
        self.window, self.tolerance, self.clock = window, tolerance, clock
        self.warning: str | None = None
        self.restart()

    def restart(self) -> None:
        """Forget the calls so far (at ``connect``)."""
        self._last: float | None = None
        self._periods: list[float] = []

    def tick(self) -> str | None:
        """Record one call; returns (and logs, once) the warning when the rate is off."""
        now = self.clock()
        if self._last is not None:
            self._periods.append(now - self._last)
        self._last = now
        if self.warning is not None or len(self._periods) < self.window:
            return None
        measured = statistics.median(self._periods)
        self._periods.clear()
        if abs(measured / self.period_s - 1.0) <= self.tolerance:
            return None
        self.warning = (
            f"{self.who}: called every {1e3 * measured:.0f} ms (median of {self.window}), but "
            f"its velocities assume {1e3 * self.period_s:.0f} ms, so each action moves the "
            f"robot {self.period_s / measured:.2f} x RMB's step: {self.hint}"
        )
        log.warning(self.warning)
        return self.warning
