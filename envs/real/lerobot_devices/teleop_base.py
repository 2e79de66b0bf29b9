"""What every teleoperator of this package shares: LeRobot's abstract methods that none of them
needs (no feedback, nothing to calibrate or configure) and action features from a key list."""

from __future__ import annotations

from typing import Any

from lerobot.teleoperators.teleoperator import Teleoperator


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
