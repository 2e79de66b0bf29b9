"""Image sizes every backend shares: the default, RMB's, and the check of a requested one."""

from __future__ import annotations

DEFAULT_IMAGE_SIZE = (128, 128)
"""``(width, height)`` of camera images unless asked otherwise (small: policies train on it)."""
RMB_IMAGE_SIZE = (640, 480)
"""``(width, height)`` RMB records."""


def check_image_size(image_size: tuple[int, int]) -> tuple[int, int]:
    """``image_size`` as two positive ints ``(width, height)``.

    Raises:
        ValueError: not two positive integers.
    """
    message = f"image_size must be two positive ints (W, H), got {image_size!r}"
    try:
        width, height = (int(v) for v in image_size)
    except (TypeError, ValueError):
        raise ValueError(message) from None
    if width <= 0 or height <= 0:
        raise ValueError(message)
    return width, height
