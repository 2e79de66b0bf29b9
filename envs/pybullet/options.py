"""The PyBullet backend's options: one typed record, checked when it is made.

Imports no simulator, so the registry can split an env's keyword arguments into these options
and the env core's without loading PyBullet.
"""

from __future__ import annotations

from dataclasses import dataclass

from rmb_lerobot.envs.images import DEFAULT_IMAGE_SIZE, check_image_size

RENDERERS = ("auto", "egl", "tiny")


@dataclass(frozen=True)
class PybulletOptions:
    """How a :class:`~rmb_lerobot.envs.pybullet.backend.PybulletBackend` builds and renders.

    Attributes:
        image_size: ``(width, height)`` of camera images.
        renderer: ``"egl"`` (PyBullet's EGL plugin: OpenGL, headless), ``"tiny"``
            (TinyRenderer, CPU) or ``"auto"`` (EGL, else TinyRenderer with a warning).
        tactile_size: ``(width, height)`` of the fingertip tactile images; None (default): the
            camera images' size, so demos recorded at one size and LeRobot env types (one image
            size for every camera) agree; RMB records both at 640 x 480.
        tactile_noise: Add the DIGIT-like sensor noise (sigma 7 of 255) to tactile images, as
            TACTO does; off gives noise-free, deterministic images.
        shadows: PyBullet's shadow pass in camera images (RMB renders with shadows).

    Raises:
        ValueError: an unknown renderer or a bad size.
    """

    image_size: tuple[int, int] = DEFAULT_IMAGE_SIZE
    renderer: str = "auto"
    tactile_size: tuple[int, int] | None = None
    tactile_noise: bool = True
    shadows: bool = True

    def __post_init__(self) -> None:
        object.__setattr__(self, "image_size", check_image_size(self.image_size))
        size = self.image_size if self.tactile_size is None else self.tactile_size
        object.__setattr__(self, "tactile_size", check_image_size(size))
        if self.renderer not in RENDERERS:
            raise ValueError(f"renderer must be one of {RENDERERS}, got {self.renderer!r}")
