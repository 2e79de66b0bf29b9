"""The scene view: what success tests and scripted experts read of a world, whatever builds it.

A simulated backend offers one (:attr:`rmb_lerobot.envs.backend.Backend.scene`); a real arm has
none (``None``: no success test, no privileged expert). Names are those the task (or the
simulator's scene builder for it) gave its objects.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence

import numpy as np


class SceneState(ABC):
    """Read-only, simulator-neutral view of the world: what success tests and experts read.

    Names are those the task gave its objects when it built them.
    """

    @abstractmethod
    def body_pose(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """World position (3,) and rotation matrix (3, 3) of a body (copies)."""

    @abstractmethod
    def geom_pose(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """World position (3,) and rotation matrix (3, 3) of a collision/visual shape."""

    @abstractmethod
    def site_pose(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """World position (3,) and rotation matrix (3, 3) of a frame marker (site)."""

    @abstractmethod
    def joint_position(self, name: str) -> np.ndarray:
        """Position coordinates of a (prop's) joint: (1,) for a hinge or slide."""

    @abstractmethod
    def joint_velocity(self, name: str) -> np.ndarray:
        """Velocity coordinates of a (prop's) joint: (6,) for a free joint (linear velocity in
        the world frame, then angular velocity)."""

    @abstractmethod
    def body_positions(self, names: Sequence[str]) -> np.ndarray:
        """World positions (n, 3) of several bodies (e.g. granular particles)."""

    @abstractmethod
    def points(self, name: str) -> np.ndarray:
        """World positions (n, 3) of a deformable object's points (cable, cloth, ring)."""
