"""The MuJoCo backend's options: one typed record, checked when it is made.

Imports no simulator, so the registry can split an env's keyword arguments into these options
and the env core's without loading MuJoCo.
"""

from __future__ import annotations

from dataclasses import dataclass

from rmb_lerobot.envs.images import DEFAULT_IMAGE_SIZE, check_image_size

FRAME_SKIP = 8  # RMB: 0.004 s x 8 = 0.032 s per control step (31.25 Hz)
# How far (m) the robot's simplified visual meshes may leave the original surface
# (rmb_lerobot.envs.mujoco.meshes, which measures it; its DEFAULT_VISUAL_MESH_ERROR is this).
DEFAULT_VISUAL_MESH_ERROR = 5e-4


@dataclass(frozen=True)
class MujocoOptions:
    """How a :class:`~rmb_lerobot.envs.mujoco.backend.MujocoBackend` builds and steps its world.

    Attributes:
        image_size: ``(width, height)`` of rendered images (sizes the offscreen buffer).
        frame_skip: Physics steps (0.004 s each) per control step.
        shadows: MuJoCo's shadow pass (off: it costs several times a plain render in software
            rendering).
        reflections: MuJoCo's reflection pass (off for the same reason).
        antialias: 4x multisampling, as RMB renders (default); ``False`` is about 2x faster at
            640x480 in software rendering, with aliased edges.
        visual_mesh_error: How far (m) the robot's simplified visual meshes may leave the
            original surface (default 0.5 mm); 0 for the original meshes. Physics is the same
            at every setting.
        tactile: Add RMB's fingertip tactile sites and read their grids
            (:mod:`rmb_lerobot.envs.sensors.tactile`). Off: the model is unchanged.

    Raises:
        ValueError: a size or count out of range.
    """

    image_size: tuple[int, int] = DEFAULT_IMAGE_SIZE
    frame_skip: int = FRAME_SKIP
    shadows: bool = False
    reflections: bool = False
    antialias: bool = True
    visual_mesh_error: float = DEFAULT_VISUAL_MESH_ERROR
    tactile: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "image_size", check_image_size(self.image_size))
        if int(self.frame_skip) != self.frame_skip or self.frame_skip < 1:
            raise ValueError(f"frame_skip must be an integer >= 1, got {self.frame_skip!r}")
        if self.visual_mesh_error < 0:
            raise ValueError(
                f"visual_mesh_error must be >= 0 metres, got {self.visual_mesh_error!r}"
            )
