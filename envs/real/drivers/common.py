"""What every arm driver shares: the driver choice, importing an SDK extra, stale-state checks.

Nothing here imports a hardware SDK: :func:`import_sdk` does, when a driver connects.
"""

from __future__ import annotations

import importlib
import ipaddress
import time
from types import ModuleType
from typing import Literal

from rmb_lerobot.envs.real.driver import StaleState

DriverKind = Literal["sdk", "sim"]
"""``"sdk"``: the vendor's SDK talks to the arm at the configured address; ``"sim"``: the arm's
MuJoCo twin (:mod:`rmb_lerobot.envs.real.twins`) answers the same calls on loopback."""

DRIVER_KINDS: tuple[str, ...] = ("sdk", "sim")


def check_driver_config(arm: str, driver: str, host: str) -> None:
    """Check a driver config's choice of driver and its address.

    The twin only ever runs on this machine, so ``driver: sim`` needs a loopback ``host``: a
    config that names a lab's address with ``sim`` is a mistake worth stopping on (and a real
    arm needs an explicit ``driver: sdk``).

    Args:
        arm: The arm's name for messages (``"UR5e"``).
        driver: The config's ``driver`` value.
        host: The config's robot address.

    Raises:
        ValueError: On an unknown driver, an empty host, or ``sim`` with a non-loopback host.
    """
    if driver not in DRIVER_KINDS:
        raise ValueError(f"{arm}: driver must be one of {DRIVER_KINDS}, got {driver!r}")
    if not host:
        raise ValueError(f"{arm}: the robot address (host) is empty; write your arm's address")
    if driver == "sim" and not is_loopback(host):
        raise ValueError(
            f"{arm}: driver 'sim' runs the twin on this machine and needs a loopback host "
            f"(127.0.0.1), got {host!r}; set driver: sdk to drive the arm at {host}"
        )


def is_loopback(host: str) -> bool:
    """Whether ``host`` is ``localhost`` or a loopback address (127.0.0.0/8, ::1).

    Args:
        host: A host name or an IP address.

    Returns:
        True for loopback, False for anything else (including other host names).
    """
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def import_sdk(module: str, extra: str, note: str = "") -> ModuleType:
    """Import a hardware SDK module, or say which extra installs it.

    Args:
        module: The SDK's module (``"rtde_control"``).
        extra: This package's extra that installs it (``"ur5e"``).
        note: Anything else the user should know (platforms the SDK has wheels for).

    Returns:
        The imported module.

    Raises:
        ImportError: Naming ``pip install 'rmb_lerobot[<extra>]'`` when the SDK is missing.
    """
    try:
        return importlib.import_module(module)
    except ImportError as error:
        raise ImportError(
            f"the {extra!r} driver needs the SDK module {module!r}, which is not installed: "
            f"pip install 'rmb_lerobot[{extra}]' (the distribution is lerobot_env_rmb: "
            f"pip install 'lerobot_env_rmb[{extra}]'){'; ' + note if note else ''}"
        ) from error


class StaleWatch:
    """Raises :class:`StaleState` when a controller timestamp stops changing.

    A reading is fresh when its timestamp differs from the previous one; a timestamp that
    stays the same for longer than ``after_s`` of wall-clock time means the state is stale
    (the controller or the data link stalled). Readings taken closer together than the
    controller's own period can share a timestamp, which is why a wall-clock grace is used.

    Args:
        what: The arm's name and address for messages.
        after_s: How long (s) a timestamp may stay unchanged.
    """

    def __init__(self, what: str, after_s: float):
        if not after_s > 0:
            raise ValueError(f"stale_after_s must be > 0, got {after_s}")
        self.what = what
        self.after_s = after_s
        self._last: float | None = None
        self._since = 0.0

    def reset(self) -> None:
        """Forget the last timestamp (after a reconnect)."""
        self._last = None

    def check(self, timestamp: float) -> None:
        """Record one reading's timestamp.

        Args:
            timestamp: The controller's timestamp of the reading.

        Raises:
            StaleState: If it has not changed for longer than ``after_s``.
        """
        now = time.monotonic()
        if self._last is None or timestamp != self._last:
            self._last, self._since = timestamp, now
            return
        if now - self._since > self.after_s:
            raise StaleState(
                f"{self.what}: stale state: the controller timestamp stayed at {timestamp:.3f} s "
                f"for {now - self._since:.2f} s (limit {self.after_s} s)"
            )
