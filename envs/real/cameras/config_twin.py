"""Config of the MuJoCo twin's camera, a LeRobot camera type (``type: rmb_twin``)."""

from __future__ import annotations

from dataclasses import dataclass

from lerobot.cameras import CameraConfig

TWIN_CAMERA_TYPE = "rmb_twin"
TWIN_VIEWS = ("front", "hand")


@CameraConfig.register_subclass(TWIN_CAMERA_TYPE)
@dataclass
class TwinCameraConfig(CameraConfig):
    """A camera rendered from a real arm's MuJoCo twin (dry runs and tests, no hardware).

    The camera renders the twin it is attached to (:meth:`TwinCamera.attach`;
    :class:`~rmb_lerobot.envs.real.device.RealRobot` attaches the twin of arm ``arm`` when it
    connects), in a background thread at ``fps``, as a RealSense does.

    Attributes:
        view: ``"hand"`` (the record's wrist camera) or ``"front"`` (a fixed view facing the
            arm, the twin's stand-in for RMB's front camera).
        arm: Which arm's twin to render (dual UR5e: 0 left, 1 right).
        use_depth: Also render depth (float metres).
        fps: Frames rendered per second (default 30, a RealSense's rate).
        width: Image width in pixels (default 640, RMB's; keep it small in tests).
        height: Image height in pixels (default 480).
    """

    view: str = "front"
    arm: int = 0
    use_depth: bool = True

    def __post_init__(self) -> None:
        if self.view not in TWIN_VIEWS:
            raise ValueError(f"twin camera view must be one of {TWIN_VIEWS}, got {self.view!r}")
        if self.arm < 0:
            raise ValueError(f"twin camera arm must be >= 0, got {self.arm}")
        self.fps = 30 if self.fps is None else self.fps
        self.width = 640 if self.width is None else self.width
        self.height = 480 if self.height is None else self.height
        if self.fps <= 0 or self.width <= 0 or self.height <= 0:
            raise ValueError(
                f"twin camera needs positive fps and size, got {self.fps} fps, "
                f"{self.width}x{self.height}"
            )
