"""Synthetic depth sequences for codec tests and benchmarks (no simulator, no downloads).

A pinhole camera (vertical field of view ``fovy``, like RMB's MuJoCo cameras) looks down at a
tilted floor with a static box on it while a sphere moves through the scene. ``clean`` frames
are the exact z-depth rounded to millimetres, like a renderer's depth buffer; ``noisy`` frames
add the error of a structured-light / stereo sensor: Gaussian noise with
sigma = 2 mm * z^2 (z in metres) and 1 % dropouts set to 0 ("no data").
"""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np

NOISE_MM_PER_M2 = 2.0
DROPOUT_FRACTION = 0.01


class DepthScene:
    """Ray-traced z-depth (metres) of floor + box + moving sphere, one frame at a time."""

    def __init__(self, width: int = 640, height: int = 480, fovy_deg: float = 45.0):
        self.width, self.height = width, height
        f = (height / 2) / math.tan(math.radians(fovy_deg) / 2)
        u = (np.arange(width) - (width - 1) / 2) / f
        v = (np.arange(height) - (height - 1) / 2) / f
        self._rx, self._ry = np.meshgrid(u, v)  # ray directions (x, y, 1)
        # Floor: 1/z is linear in the image for a plane; 0.8 m at the bottom row, 1.6 m at the top.
        half = (height - 1) / 2 / f
        a = (1 / 0.8 - 1 / 1.6) / (2 * half)
        inv_floor = 0.9375 + a * self._ry + 0.05 * self._rx
        floor = 1.0 / inv_floor
        # Static box: its top face is a plane 12 cm above the floor, over a fixed image rectangle.
        box = np.zeros((height, width), dtype=bool)
        box[int(0.52 * height) : int(0.8 * height), int(0.12 * width) : int(0.35 * width)] = True
        box_top = 1.0 / (inv_floor + 0.12)
        self._static = np.where(box, np.minimum(floor, box_top), floor)

    def frame(self, t: int) -> np.ndarray:
        """Depth in metres (float64, HxW) at frame ``t``: the sphere moves on a Lissajous path."""
        radius = 0.07
        cx = 0.25 * math.sin(2 * math.pi * t / 160)
        cy = 0.12 * math.sin(2 * math.pi * t / 110 + 0.5)
        cz = 1.0 + 0.1 * math.cos(2 * math.pi * t / 200)
        # Ray (rx, ry, 1) * s hits the sphere where |s*r - c|^2 = radius^2; z-depth = s.
        rr = self._rx**2 + self._ry**2 + 1
        rc = self._rx * cx + self._ry * cy + cz
        disc = rc**2 - rr * (cx**2 + cy**2 + cz**2 - radius**2)
        hit = disc > 0
        s = np.where(hit, (rc - np.sqrt(np.where(hit, disc, 0))) / rr, np.inf)
        return np.minimum(self._static, s)


def clean_depth_mm(n_frames: int, width: int = 640, height: int = 480) -> Iterator[np.ndarray]:
    """Rendered-like frames: exact depth rounded to uint16 millimetres."""
    scene = DepthScene(width, height)
    for t in range(n_frames):
        yield np.rint(scene.frame(t) * 1000).astype(np.uint16)


def noisy_depth_mm(
    n_frames: int, width: int = 640, height: int = 480, seed: int = 0
) -> Iterator[np.ndarray]:
    """Sensor-like frames: N(0, (2 mm * z^2)^2) noise and 1 % zeros, uint16 millimetres."""
    scene = DepthScene(width, height)
    rng = np.random.default_rng(seed)
    for t in range(n_frames):
        z = scene.frame(t)
        mm = z * 1000 + rng.standard_normal(z.shape) * (NOISE_MM_PER_M2 * z**2)
        mm = np.rint(np.clip(mm, 0, 65535)).astype(np.uint16)
        mm[rng.random(z.shape) < DROPOUT_FRACTION] = 0
        yield mm
