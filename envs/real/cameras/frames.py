"""One camera frame as RMB records it, read from any LeRobot camera.

RMB stores per camera an RGB image, a depth image in metres and the vertical field of view
(``fovy``, degrees, from the intrinsics: ``2 atan(h / (2 fy))``; RMB keeps the depth stream's).
:func:`read_frame` gets those from a LeRobot camera: a RealSense with ``use_depth`` (depth in
mm, converted to metres), an OpenCV camera (RGB only) or the twin's camera.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

log = logging.getLogger(__name__)

DEFAULT_FOVY = 45.0
"""fovy (degrees) of a camera without intrinsics (an OpenCV webcam) unless one is given."""


@dataclass(frozen=True)
class CameraFrame:
    """One frame of one camera.

    Attributes:
        rgb: ``uint8 (H, W, 3)`` RGB image.
        depth: ``float32 (H, W)`` z-depth in metres, or ``None`` for a colour-only camera.
        fovy: Vertical field of view (degrees).
    """

    rgb: np.ndarray
    depth: np.ndarray | None
    fovy: float


def fovy_from_intrinsics(height: int, fy: float) -> float:
    """RMB's vertical field of view of a pinhole camera.

    Args:
        height: Image height (pixels).
        fy: Focal length in pixels along y.

    Returns:
        ``2 atan(height / (2 fy))`` in degrees.
    """
    return math.degrees(2.0 * math.atan(height / (2.0 * fy)))


def camera_fovy(camera: Any, default: float | None = None) -> float:
    """The vertical field of view of a connected camera.

    The twin's camera knows its own; a RealSense reads its stream intrinsics (the depth
    stream's when depth is on, as RMB does, else the colour stream's); anything else gets
    ``default`` (or :data:`DEFAULT_FOVY`, with a warning).

    Args:
        camera: A connected LeRobot camera.
        default: fovy (degrees) to use where the camera has no intrinsics.

    Returns:
        fovy in degrees.
    """
    fovy = getattr(camera, "fovy", None)
    if isinstance(fovy, float):
        return fovy
    profile = getattr(camera, "rs_profile", None)
    if profile is not None:
        import pyrealsense2 as rs  # the realsense extra; the camera could not exist without it

        stream = rs.stream.depth if getattr(camera, "use_depth", False) else rs.stream.color
        intrinsics = profile.get_stream(stream).as_video_stream_profile().get_intrinsics()
        return fovy_from_intrinsics(intrinsics.height, intrinsics.fy)
    if default is not None:
        return float(default)
    log.warning("%s has no intrinsics: fovy %.1f deg assumed; pass one", camera, DEFAULT_FOVY)
    return DEFAULT_FOVY


def read_frame(camera: Any, fovy: float, max_age_ms: int = 500) -> CameraFrame:
    """The newest frame of a connected LeRobot camera, without waiting for a new one.

    The control loop must not wait for a camera running slower than it (30 fps against
    50 Hz), so this peeks at the newest frame the camera's own thread captured
    (``read_latest``), as RMB reads the newest RealSense frame.

    Args:
        camera: A connected LeRobot camera (``RealSenseCamera``, ``OpenCVCamera``,
            :class:`~rmb_lerobot.envs.real.cameras.TwinCamera`).
        fovy: Its vertical field of view (:func:`camera_fovy`).
        max_age_ms: Refuse a frame older than this.

    Returns:
        The frame; ``depth`` is ``None`` unless the camera streams depth.

    Raises:
        TimeoutError: The newest frame is older than ``max_age_ms`` (the camera stalled).
        RuntimeError: The camera has no frame yet.
    """
    if hasattr(camera, "read_frame"):  # the twin's camera: RGB and depth of one render
        return camera.read_frame(max_age_ms)
    rgb = np.asarray(camera.read_latest(max_age_ms=max_age_ms))
    depth = None
    if getattr(camera, "use_depth", False) and hasattr(camera, "read_latest_depth"):
        depth_mm = np.asarray(camera.read_latest_depth(max_age_ms=max_age_ms))
        depth = depth_mm.reshape(depth_mm.shape[:2]).astype(np.float32) * np.float32(1e-3)
    return CameraFrame(rgb=rgb, depth=depth, fovy=fovy)
