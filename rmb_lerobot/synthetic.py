"""Synthetic UR5e episodes (no simulator, no downloads) for the quick start and tests.

The steps carry what an RMB recorder writes for a UR5e: joint and gripper positions
(measured lagging the command), velocities, wrench, reward, time at RMB's 31.25 Hz, and RGB +
depth for each camera, rendered from :class:`rmb_lerobot.codecs.synthetic.DepthScene`.
End-effector poses and ``_rel`` keys are left for the writer to derive.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np

from rmb_lerobot import keys as K
from rmb_lerobot.codecs.synthetic import DepthScene

UR5E_CONTROL_HZ = 31.25  # timestep 0.004 s x frame_skip 8, as in RMB's MuJoCo UR5e envs
UR5E_HOME = np.array([np.pi / 2, -np.pi / 2, np.pi / 2, -np.pi / 2, -np.pi / 2, 0.0])
FOVY_DEG = 45.0


def _rgb_from_depth(depth_m: np.ndarray, t: int) -> np.ndarray:
    """A textured, shaded RGB image consistent with the depth image."""
    h, w = depth_m.shape
    v, u = np.mgrid[0:h, 0:w]
    checker = (((u + 2 * t) // 32 + v // 32) % 2).astype(np.float64)
    shade = np.clip(1.6 - depth_m, 0.2, 1.0)
    rgb = np.stack([shade * (0.5 + 0.4 * checker), shade * 0.7, shade * (0.9 - 0.4 * checker)], -1)
    return (rgb * 255).astype(np.uint8)


def ur5e_steps(
    num_steps: int,
    cameras: tuple[str, ...] = ("front", "hand"),
    image_size: tuple[int, int] = (640, 480),
    seed: int = 0,
) -> Iterator[dict[str, Any]]:
    """Yield ``num_steps`` step dicts of a smooth reaching-and-grasping motion."""
    rng = np.random.default_rng(seed)
    width, height = image_size
    scene = DepthScene(width, height, FOVY_DEG)
    phase = rng.uniform(0, 2 * np.pi, 6)
    measured = np.concatenate([UR5E_HOME, [0.0]])
    for i in range(num_steps):
        s = i / max(num_steps - 1, 1)
        arm = UR5E_HOME + 0.3 * np.sin(2 * np.pi * s + phase) * np.array([1, 0.5, 0.5, 1, 1, 1])
        gripper = 255.0 * float(s > 0.6)
        command = np.concatenate([arm, [gripper]])
        previous = measured
        measured = measured + 0.5 * (command - measured) + rng.normal(0, 1e-4, 7)
        step: dict[str, Any] = {
            K.TIME: i / UR5E_CONTROL_HZ,
            K.REWARD: float(s > 0.9),
            K.MEASURED_JOINT_POS: measured,
            K.COMMAND_JOINT_POS: command,
            K.MEASURED_JOINT_VEL: (measured - previous) * UR5E_CONTROL_HZ,
            K.COMMAND_JOINT_VEL: np.zeros(7),
            K.MEASURED_GRIPPER_JOINT_POS: measured[6:7],
            K.COMMAND_GRIPPER_JOINT_POS: command[6:7],
            K.MEASURED_EEF_WRENCH: rng.normal(0, 0.5, 6),
        }
        depth = scene.frame(i).astype(np.float32)
        for camera in cameras:
            step[K.rgb_image_key(camera)] = _rgb_from_depth(depth, i)
            step[K.depth_image_key(camera)] = depth
        yield step


def ur5e_attrs(cameras: tuple[str, ...] = ("front", "hand"), **overrides: Any) -> dict[str, Any]:
    """Episode attributes as RMB's MujocoUR5e recorder writes them."""
    attrs: dict[str, Any] = {
        K.ATTR_DEMO_NAME: "synthetic",
        K.ATTR_TASK_DESC: "Reach and close the gripper (synthetic data).",
        K.ATTR_ENV: "MujocoUR5eCableEnv",
        K.ATTR_WORLD_IDX: 0,
        K.ATTR_CAMERA_NAMES: list(cameras),
    }
    attrs.update({K.fovy_attr(camera): FOVY_DEG for camera in cameras})
    attrs.update(overrides)
    return attrs
