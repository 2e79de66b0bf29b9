"""Cameras of the real robots: LeRobot's own camera classes (RealSense with depth, OpenCV)
and, for dry runs and tests, :class:`TwinCamera` rendering a twin (LeRobot type
``rmb_twin``); :func:`read_frame` turns any of them into RMB's RGB + depth (m) + fovy."""

from rmb_lerobot.envs.real.cameras.config_twin import TWIN_CAMERA_TYPE, TwinCameraConfig
from rmb_lerobot.envs.real.cameras.frames import (
    DEFAULT_FOVY,
    CameraFrame,
    camera_fovy,
    fovy_from_intrinsics,
    read_frame,
)
from rmb_lerobot.envs.real.cameras.twin import TwinCamera

__all__ = [
    "DEFAULT_FOVY",
    "TWIN_CAMERA_TYPE",
    "CameraFrame",
    "TwinCamera",
    "TwinCameraConfig",
    "camera_fovy",
    "fovy_from_intrinsics",
    "read_frame",
]
