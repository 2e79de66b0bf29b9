"""Depth frames -> the fixed-size point clouds DP3 encodes, with rmb_lerobot.pointcloud.

Runs on the CPU in NumPy (back-projection, crop, ``fpsample`` farthest-point sampling) because
that is where the sampling is fast; clouds are memoised by frame content, so after the first
epoch training decodes depth but does not sample it again.
"""

from __future__ import annotations

import hashlib
import json
import logging
from collections import OrderedDict
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import Tensor

from rmb_lerobot import keys as K
from rmb_lerobot import lerobot_names as N
from rmb_lerobot.pointcloud import (
    crop_points,
    depth_to_points,
    farthest_point_sample,
    transform_points,
)

from .configuration_dp3 import (
    DEFAULT_CAMERA_FOVY,
    DEPTH_UNITS,
    PointCloudUnetConfig,
    checked_camera_pose,
)

logger = logging.getLogger(__name__)


class DepthPointClouds:
    """``(..., 1, H, W)`` depth (+ ``(..., 3, H, W)`` RGB) -> ``(..., num_points, 3 or 6)``.

    Points are in metres, colours in [0, 1]. The frame is the config's
    :attr:`~PointCloudUnetConfig.resolved_crop_frame`: the camera's (x right, y down, z forward)
    or, with a known ``camera_pose``, the world's (z up), where they are also cropped.
    """

    def __init__(self, config: PointCloudUnetConfig):
        if config.camera_fovy is None:
            raise ValueError("camera_fovy is unset: see the policy config's camera_fovy")
        self.fovy = float(config.camera_fovy)
        self.scale = DEPTH_UNITS[config.depth_unit]
        self.stride = config.depth_stride
        self.num_points = config.num_points
        low, high = config.crop_box()
        self.frame = config.resolved_crop_frame
        self.pose = None if self.frame == "camera" else np.asarray(config.camera_pose)
        self.crop = (np.asarray(low), np.asarray(high))
        self.cache_size = config.point_cloud_cache_size
        self._cache: OrderedDict[bytes, np.ndarray] = OrderedDict()

    def __call__(self, depth: Tensor, rgb: Tensor | None = None) -> Tensor:
        lead = depth.shape[:-3]
        s = self.stride
        frames = depth.detach().reshape(-1, *depth.shape[-2:])[:, ::s, ::s].cpu().numpy()
        colors = None
        if rgb is not None:
            colors = rgb.detach().reshape(-1, *rgb.shape[-3:])[:, :, ::s, ::s].cpu().numpy()
            colors = np.ascontiguousarray(colors.transpose(0, 2, 3, 1))
        clouds = np.stack(
            [
                self._cached(frame, None if colors is None else colors[i])
                for i, frame in enumerate(frames)
            ]
        )
        return torch.from_numpy(clouds).to(depth.device).reshape(*lead, *clouds.shape[1:])

    def _cached(self, depth: np.ndarray, rgb: np.ndarray | None) -> np.ndarray:
        if self.cache_size <= 0:
            return self.cloud(depth, rgb)
        digest = hashlib.blake2b(np.ascontiguousarray(depth).data, digest_size=16)
        if rgb is not None:
            digest.update(rgb.data)
        key = digest.digest()
        cloud = self._cache.get(key)
        if cloud is None:
            cloud = self._cache[key] = self.cloud(depth, rgb)
            if len(self._cache) > self.cache_size:
                self._cache.popitem(last=False)
        else:
            self._cache.move_to_end(key)
        return cloud

    def cloud(self, depth: np.ndarray, rgb: np.ndarray | None = None) -> np.ndarray:
        """One (H, W) depth frame in the configured unit (+ (H, W, 3) RGB) -> (N, 3 or 6)."""
        points, colors = depth_to_points(depth.astype(np.float32) * self.scale, self.fovy, rgb)
        if self.pose is not None:
            points = transform_points(points, matrix=self.pose)
        points, colors = crop_points(points, colors, min_bound=self.crop[0], max_bound=self.crop[1])
        if len(points) == 0:
            raise ValueError(
                f"no depth pixel lies in the crop box {self.crop[0]}..{self.crop[1]} m "
                f"({self.frame} frame): check crop_min/crop_max, crop_frame, depth_unit, the camera"
            )
        points, colors = farthest_point_sample(points, self.num_points, colors)
        if colors is None:
            return points
        return np.concatenate([points, colors], axis=1)


def _episode_attrs(meta: Any) -> list[dict[str, Any]]:
    """Every episode's attributes in a converted dataset's ``meta/rmb.json`` ([] if none)."""
    root = getattr(meta, "root", None)
    path = Path(root) / N.RMB_METADATA_PATH if root is not None else None
    if path is None or not path.is_file():
        return []
    return [ep.get("attrs", {}) for ep in json.loads(path.read_text()).get("episodes", [])]


def pose_from_dataset(meta: Any, camera: str) -> list[list[float]] | None:
    """The camera's world pose recorded in ``meta/rmb.json`` (:func:`K.camera_pose_attr`), if
    every episode records the same one; None if none does; ValueError if they disagree or some
    episodes lack it (a world-frame cloud needs one pose for all)."""
    name = K.camera_pose_attr(camera)
    episodes = _episode_attrs(meta)
    poses = [ep.get(name) for ep in episodes]
    known = [checked_camera_pose(p, f"{name} in {N.RMB_METADATA_PATH}") for p in poses if p]
    if not known:
        return None
    if len(known) != len(poses):
        raise ValueError(
            f"{len(poses) - len(known)} of {len(poses)} episodes lack {name!r} (the pose of "
            f"camera {camera!r}): use --policy.crop_frame=camera or re-record them"
        )
    first = np.asarray(known[0])
    for pose in known[1:]:
        if not np.allclose(pose, first, atol=1e-6):
            raise ValueError(
                f"episodes disagree on the pose of camera {camera!r} ({name}): "
                f"{first.tolist()} vs {pose}"
            )
    return known[0]


def resolve_camera_pose(config: PointCloudUnetConfig, dataset_meta: Any | None) -> None:
    """Fill ``config.camera_pose`` from the dataset; check it against the dataset if it is set;
    then check the crop (``crop_frame="world"`` without a pose raises, naming it)."""
    camera = N.camera_of_image_key(config.depth_key).removesuffix(N.DEPTH_CAMERA_SUFFIX)
    try:
        recorded = pose_from_dataset(dataset_meta, camera) if dataset_meta is not None else None
    except ValueError as exc:
        if config.crop_frame != "camera":
            raise
        logger.warning("%s: camera frame, pose not used: %s", config.type, exc)
        recorded = None
    if config.camera_pose is None:
        config.camera_pose = recorded
    elif recorded is not None and not np.allclose(config.camera_pose, recorded, atol=1e-6):
        raise ValueError(
            f"camera_pose={config.camera_pose} but the dataset records {recorded} for {camera!r}"
        )
    config.crop_box()
    logger.info("%s: point clouds in the %s frame", config.type, config.resolved_crop_frame)


def fovy_from_dataset(meta: Any, camera: str) -> float | None:
    """The camera's fovy recorded in a converted dataset's ``meta/rmb.json``, if any."""
    episodes = _episode_attrs(meta)
    values = {ep.get(K.fovy_attr(camera)) for ep in episodes} - {None}
    if len(values) > 1:
        raise ValueError(f"episodes disagree on the fovy of camera {camera!r}: {sorted(values)}")
    return float(values.pop()) if values else None


def resolve_camera_fovy(config: PointCloudUnetConfig, dataset_meta: Any | None) -> None:
    """Fill ``config.camera_fovy`` from the dataset (or the default); check it if it is set."""
    camera = N.camera_of_image_key(config.depth_key).removesuffix(N.DEPTH_CAMERA_SUFFIX)
    recorded = fovy_from_dataset(dataset_meta, camera) if dataset_meta is not None else None
    if config.camera_fovy is None:
        if recorded is None:
            logger.warning(
                "DP3: no fovy recorded for camera %r; using %.1f deg (set --policy.camera_fovy)",
                camera,
                DEFAULT_CAMERA_FOVY,
            )
        config.camera_fovy = DEFAULT_CAMERA_FOVY if recorded is None else recorded
    elif recorded is not None and abs(recorded - config.camera_fovy) > 1e-6:
        raise ValueError(
            f"camera_fovy={config.camera_fovy} but the dataset records {recorded} for {camera!r}"
        )


def resolve_camera(config: PointCloudUnetConfig, dataset_meta: Any | None) -> None:
    """The depth camera's intrinsics and extrinsics for a point-cloud policy being built:
    :func:`resolve_camera_fovy`, then :func:`resolve_camera_pose` (which also checks the crop)."""
    resolve_camera_fovy(config, dataset_meta)
    resolve_camera_pose(config, dataset_meta)
