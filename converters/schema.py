"""What a converted dataset holds: RMB keys -> LeRobot features, and per-episode arrays.

- ``observation.state`` / ``action``: the selected state / action keys concatenated in the
  order given (RMB's ``--state_keys`` / ``--action_keys``), absolute eef poses in the 9-number
  policy view, names ``<rmb key>.<component>``.
- ``observation.images.<camera>``: RGB video, or with ``image_features`` a LeRobot ``image``
  feature (lossless PNG bytes in the parquet rows: the episodes' own frames, no AV1 loss);
  ``observation.images.<camera>_depth``: depth video flagged ``is_depth_map`` (LeRobot's own
  depth encoder).
- Every other low-dimensional key keeps its own feature (:func:`lerobot_names.rmb_feature_key`),
  stored as recorded; absolute eef poses that went into the state or action in the lossy policy
  view are kept raw as well, so a round trip restores them exactly.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rmb_lerobot import keys as K
from rmb_lerobot import lerobot_names as N
from rmb_lerobot.converters.cast import to_float32
from rmb_lerobot.converters.components import component_names, infer_layout, stored_dim
from rmb_lerobot.converters.skip import skip_sequence
from rmb_lerobot.pose import POSE_DIM, pose_to_policy

FLOAT = "float32"
VIDEO = "video"
IMAGE = "image"  # LeRobot's dtype of images stored in the parquet rows (PNG bytes)
_IMAGE_NAMES = ["height", "width", "channels"]


def uses_policy_view(key: str) -> bool:
    """Absolute eef poses are shown to policies as position + 6-D rotation (as RMB does)."""
    spec = K.KEYS.get(key)
    return spec is not None and spec.quantity is K.Quantity.EEF_POSE and not spec.is_relative


def policy_view(key: str, values: np.ndarray) -> np.ndarray:
    """``(T, ...)`` values of ``key`` as ``(T, d)`` numbers in the policy's view."""
    flat = np.asarray(values, dtype=np.float64).reshape(len(values), -1)
    if not uses_policy_view(key):
        return flat
    poses = flat.reshape(len(flat), -1, POSE_DIM)
    return pose_to_policy(poses).reshape(len(flat), -1)


@dataclass(frozen=True)
class DatasetSchema:
    """The feature layout shared by every episode of one conversion."""

    state_keys: tuple[str, ...]
    action_keys: tuple[str, ...]
    extra_keys: tuple[str, ...]  # kept as their own features
    dims: Mapping[str, int]  # numbers per step as stored in the episodes
    cameras: tuple[str, ...]  # RGB cameras
    depth_cameras: tuple[str, ...]
    image_shapes: Mapping[str, tuple[int, int]]  # RMB image key -> (height, width)
    layout: K.RobotLayout
    rgb_dtype: str = VIDEO  # LeRobot dtype of the RGB cameras: VIDEO or IMAGE

    @property
    def lowdim_keys(self) -> tuple[str, ...]:
        """Every low-dimensional RMB key an episode must provide."""
        return tuple(dict.fromkeys((*self.state_keys, *self.action_keys, *self.extra_keys)))

    def image_keys(self) -> dict[str, str]:
        """Dataset image/video feature -> RMB image key."""
        keys = {N.image_key(c): K.rgb_image_key(c) for c in self.cameras}
        keys.update({N.depth_image_key(c): K.depth_image_key(c) for c in self.depth_cameras})
        return keys

    def _vector_names(self, keys: Sequence[str]) -> list[str]:
        names = []
        for key in keys:
            dim = self._policy_dim(key)
            comps = component_names(key, dim, self.layout, policy=True)
            names += [f"{key}.{comp}" for comp in comps]
        return names

    def _policy_dim(self, key: str) -> int:
        dim = self.dims[key]
        return dim // POSE_DIM * 9 if uses_policy_view(key) else dim

    def features(self) -> dict[str, dict]:
        """The ``features`` argument of ``LeRobotDataset.create``."""
        features: dict[str, dict] = {}
        for feature, keys in ((N.STATE, self.state_keys), (N.ACTION_KEY, self.action_keys)):
            names = self._vector_names(keys)
            features[feature] = {"dtype": FLOAT, "shape": (len(names),), "names": names}
        for camera in self.cameras:
            height, width = self.image_shapes[K.rgb_image_key(camera)]
            features[N.image_key(camera)] = {
                "dtype": self.rgb_dtype,
                "shape": (height, width, 3),
                "names": _IMAGE_NAMES,
            }
        for camera in self.depth_cameras:
            height, width = self.image_shapes[K.depth_image_key(camera)]
            features[N.depth_image_key(camera)] = {
                "dtype": VIDEO,
                "shape": (height, width, 1),
                "names": _IMAGE_NAMES,
                "info": {"is_depth_map": True},
            }
        for key in self.extra_keys:
            names = component_names(key, self.dims[key], self.layout, policy=False)
            features[N.rmb_feature_key(key)] = {
                "dtype": FLOAT,
                "shape": (self.dims[key],),
                "names": names,
            }
        return features

    def episode_arrays(
        self,
        lowdim: Mapping[str, np.ndarray],
        skip: int,
        *,
        path: str | Path | None = None,
        allow_non_finite: bool = False,
    ) -> dict[str, np.ndarray]:
        """Per-frame float32 arrays ``(T', d)`` of every low-dimensional feature, subsampled.

        Each key is cast with :func:`.cast.to_float32` (errors name ``path``, key and step).
        """
        skipped = {key: skip_sequence(key, lowdim[key], skip) for key in self.lowdim_keys}

        def cast(key: str, values: np.ndarray) -> np.ndarray:
            flat = values.reshape(len(values), -1)
            return to_float32(flat, key, path=path, skip=skip, allow_non_finite=allow_non_finite)

        arrays = {}
        for feature, keys in ((N.STATE, self.state_keys), (N.ACTION_KEY, self.action_keys)):
            for key in keys:
                if uses_policy_view(key):
                    cast(key, skipped[key])  # errors name the recorded component, not the view's
            parts = [cast(key, policy_view(key, skipped[key])) for key in keys]
            arrays[feature] = np.concatenate(parts, axis=1)
        for key in self.extra_keys:
            arrays[N.rmb_feature_key(key)] = cast(key, skipped[key])
        return arrays


def build_schema(
    lowdim_shapes: Mapping[str, tuple[int, ...]],
    image_shapes: Mapping[str, tuple[int, int]],
    state_keys: Sequence[str],
    action_keys: Sequence[str],
    cameras: Sequence[str],
    depth: bool,
    *,
    extra_keys: bool = True,
    image_features: bool = False,
) -> DatasetSchema:
    """The schema for episodes whose low-dimensional keys have ``lowdim_shapes`` (``(T, ...)``).

    ``image_shapes`` maps the episode's RMB image keys to ``(height, width)``; a camera
    contributes its RGB stream if it has one and its depth stream if ``depth``. Pointcloud keys
    are not converted: they are computed from depth and ``fovy``, which are kept. With
    ``extra_keys`` false, no key outside state and action gets a feature of its own (a lean
    dataset: LeRobot reads every column of each sampled row). With ``image_features`` the RGB
    cameras are LeRobot ``image`` features instead of videos (depth stays video).
    """
    dims = {key: stored_dim(np.empty((0, *shape[1:]))) for key, shape in lowdim_shapes.items()}
    selected = set(state_keys) | set(action_keys)
    extra = tuple(
        key
        for key in lowdim_shapes
        if extra_keys
        and not K.is_pointcloud_key(key)
        and (key not in selected or uses_policy_view(key))
    )
    rgb = tuple(c for c in cameras if K.rgb_image_key(c) in image_shapes)
    depth_cameras = tuple(c for c in cameras if depth and K.depth_image_key(c) in image_shapes)
    return DatasetSchema(
        state_keys=tuple(state_keys),
        action_keys=tuple(action_keys),
        extra_keys=extra,
        dims=dims,
        cameras=rgb,
        depth_cameras=depth_cameras,
        image_shapes=dict(image_shapes),
        layout=infer_layout(dims),
        rgb_dtype=IMAGE if image_features else VIDEO,
    )
