"""Whether this machine can open a window, and rerun for the viewers that would open one.

One answer for every tool that shows something (``rmb-data view``, ``rmb-teleop --live-view``,
the keyboard's pynput listener), so a headless machine is told the same everywhere.
"""

from __future__ import annotations

import os
import sys
from types import ModuleType


def has_display() -> bool:
    """Whether a desktop session exists here (macOS/Windows, or an X11/Wayland display)."""
    if sys.platform in ("darwin", "win32"):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def import_rerun(feature: str = "this viewer") -> ModuleType:
    """``rerun``, or an ImportError that names the extra to install.

    Args:
        feature: What needs it, for the message (e.g. ``"rmb-data view"``).

    Raises:
        ImportError: rerun-sdk is not installed.
    """
    try:
        import rerun
    except ImportError as exc:
        raise ImportError(
            f"{feature} needs rerun-sdk, in the viz extra: pip install 'lerobot_env_rmb[viz]' "
            "(or pip install 'rerun-sdk>=0.24,<0.34')"
        ) from exc
    return rerun
