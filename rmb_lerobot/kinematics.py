"""Forward kinematics from Denavit-Hartenberg tables.

RMB derives ``*_eef_pose`` from joint positions. In simulation the MuJoCo model is the source
of truth; for real-robot logs (or when no model is at hand) the manufacturer's DH table gives
the same flange pose. :class:`DHChain` instances are forward-kinematics callables accepted by
:class:`rmb_lerobot.EpisodeWriter` (``fk=UR5E``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rmb_lerobot.pose import matrix_to_pose


@dataclass(frozen=True)
class DHChain:
    """A serial arm in standard DH parameters (a, d, alpha per joint), base to flange."""

    a: tuple[float, ...]
    d: tuple[float, ...]
    alpha: tuple[float, ...]

    @property
    def num_joints(self) -> int:
        return len(self.a)

    def transform(self, q: np.ndarray) -> np.ndarray:
        """Flange pose as a 4x4 transform for joint angles ``q`` (extra entries, e.g. the
        gripper value RMB appends, are ignored)."""
        q = np.asarray(q, dtype=np.float64)
        if q.shape[-1] < self.num_joints:
            raise ValueError(f"expected at least {self.num_joints} joint values, got {q.shape}")
        out = np.eye(4)
        for theta, a, d, alpha in zip(
            q[: self.num_joints], self.a, self.d, self.alpha, strict=True
        ):
            ct, st, ca, sa = np.cos(theta), np.sin(theta), np.cos(alpha), np.sin(alpha)
            out = out @ np.array(
                [
                    [ct, -st * ca, st * sa, a * ct],
                    [st, ct * ca, -ct * sa, a * st],
                    [0, sa, ca, d],
                    [0, 0, 0, 1],
                ]
            )
        return out

    def __call__(self, q: np.ndarray) -> np.ndarray:
        """Flange pose ``(tx, ty, tz, qw, qx, qy, qz)``: the signature EpisodeWriter expects."""
        return matrix_to_pose(self.transform(q))


# Universal Robots' published UR5e DH parameters (metres, radians).
UR5E = DHChain(
    a=(0.0, -0.425, -0.3922, 0.0, 0.0, 0.0),
    d=(0.1625, 0.0, 0.0, 0.1333, 0.0997, 0.0996),
    alpha=(np.pi / 2, 0.0, 0.0, np.pi / 2, -np.pi / 2, 0.0),
)
