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
from rmb_lerobot.pointcloud import crop_points, depth_to_points, farthest_point_sample

from .configuration_dp3 import DEFAULT_CAMERA_FOVY, DEPTH_UNITS, PointCloudUnetConfig

logger = logging.getLogger(__name__)


class DepthPointClouds:
    """``(..., 1, H, W)`` depth (+ ``(..., 3, H, W)`` RGB) -> ``(..., num_points, 3 or 6)``.

    Points are in metres in the camera frame (x right, y down, z forward), colours in [0, 1].
    """

    def __init__(self, config: PointCloudUnetConfig):
        if config.camera_fovy is None:
            raise ValueError("camera_fovy is unset: see the policy config's camera_fovy")
        self.fovy = float(config.camera_fovy)
        self.scale = DEPTH_UNITS[config.depth_unit]
        self.stride = config.depth_stride
        self.num_points = config.num_points
        self.crop = (np.asarray(config.crop_min), np.asarray(config.crop_max))
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
        points, colors = crop_points(points, colors, min_bound=self.crop[0], max_bound=self.crop[1])
        if len(points) == 0:
            raise ValueError(
                f"no depth pixel lies in the crop box {self.crop[0]}..{self.crop[1]} m (camera "
                "frame): check crop_min/crop_max, depth_unit and the camera"
            )
        points, colors = farthest_point_sample(points, self.num_points, colors)
        if colors is None:
            return points
        return np.concatenate([points, colors], axis=1)


def fovy_from_dataset(meta: Any, camera: str) -> float | None:
    """The camera's fovy recorded in a converted dataset's ``meta/rmb.json``, if any."""
    root = getattr(meta, "root", None)
    path = Path(root) / N.RMB_METADATA_PATH if root is not None else None
    if path is None or not path.is_file():
        return None
    episodes = json.loads(path.read_text()).get("episodes", [])
    values = {ep["attrs"].get(K.fovy_attr(camera)) for ep in episodes} - {None}
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
