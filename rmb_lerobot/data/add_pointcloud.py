"""Add point clouds computed from depth to episodes (RMB's AddPointCloudToRmbData), atomically.

Per camera and step, as the original: RGB and depth resized to ``image_size`` (RMB's default
84 x 84), back-projected with the camera's ``fovy`` (:mod:`rmb_lerobot.pointcloud`; camera frame
x right, y down, z forward), rotated by ``rpy_angle`` (degrees, ``Rz @ Ry @ Rx``), cropped to
the box ``min_bound``..``max_bound`` and reduced to ``num_points`` by farthest-point sampling
from the first point. Where the episode already holds raw clouds ``<camera>_pointcloud_raw``,
those are rotated, cropped and sampled instead (and ``image_size`` is recorded as ``[-1, -1]``),
as in the original.

Stored as RMB names it: dataset ``<camera>_pointcloud`` (T, num_points, 6) float32, xyz metres
+ rgb in [0, 1], and attributes ``<camera>_pointcloud_image_size``, ``_min_bound``,
``_max_bound``, ``_rpy_angle``. Differences from the original, all small: depth is resized by
nearest neighbour (linear interpolation invents depths between foreground and background), the
crop keeps points on the faces of the box, and when fewer than ``num_points`` remain they are
repeated cyclically instead of repeating the last one.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from tqdm import tqdm

from rmb_lerobot import keys as K
from rmb_lerobot.data.edit import edit_hdf5
from rmb_lerobot.episode import Episode, find_episodes, open_episode
from rmb_lerobot.errors import MissingKeyError, RmbFormatError
from rmb_lerobot.pointcloud import crop_points, depth_to_pointcloud, farthest_point_sample

RAW_SUFFIX = "_raw"
ATTR_SUFFIXES = ("_image_size", "_min_bound", "_max_bound", "_rpy_angle")
_CHUNK = 32


@dataclass(frozen=True)
class PointCloudOptions:
    """RMB's defaults (AddPointCloudToRmbData's command-line defaults)."""

    image_size: tuple[int, int] = (84, 84)  # (width, height)
    min_bound: tuple[float, float, float] = (-0.4, -0.4, -0.4)
    max_bound: tuple[float, float, float] = (1.0, 1.0, 1.0)
    rpy_angle: tuple[float, float, float] = (0.0, 0.0, 0.0)  # degrees
    num_points: int = 512

    def __post_init__(self):
        if len(self.image_size) != 2 or min(self.image_size) < 1:
            raise ValueError(
                f"image_size must be two positive numbers (width, height), got {self.image_size}"
            )
        if self.num_points < 1:
            raise ValueError(f"num_points must be >= 1, got {self.num_points}")
        if any(lo > hi for lo, hi in zip(self.min_bound, self.max_bound, strict=True)):
            raise ValueError(f"min_bound {self.min_bound} exceeds max_bound {self.max_bound}")


def rpy_matrix(rpy_deg: Sequence[float]) -> np.ndarray:
    """``Rz(yaw) @ Ry(pitch) @ Rx(roll)`` from degrees, as RMB's euler_to_rotation_matrix."""
    r, p, y = np.deg2rad(np.asarray(rpy_deg, dtype=np.float64))
    rx = np.array([[1, 0, 0], [0, np.cos(r), -np.sin(r)], [0, np.sin(r), np.cos(r)]])
    ry = np.array([[np.cos(p), 0, np.sin(p)], [0, 1, 0], [-np.sin(p), 0, np.cos(p)]])
    rz = np.array([[np.cos(y), -np.sin(y), 0], [np.sin(y), np.cos(y), 0], [0, 0, 1]])
    return rz @ ry @ rx


def _check(episode: Episode, camera: str, overwrite: bool) -> None:
    """Refuse before any work: existing clouds without overwrite, missing images or fovy."""
    key = K.pointcloud_key(camera)
    if key in episode and not overwrite:
        raise RmbFormatError(
            "point cloud already exists; pass --overwrite to replace it", path=episode.path, key=key
        )
    if key + RAW_SUFFIX in episode:
        return
    for needed in (K.rgb_image_key(camera), K.depth_image_key(camera)):
        if needed not in episode:
            cameras = episode.camera_names
            raise MissingKeyError(
                f"camera {camera!r} has no {needed!r} (cameras with images: {cameras})",
                path=episode.path,
                key=needed,
            )
    episode.fovy(camera)  # raises naming the attribute if missing or invalid


def _sample(points, colors, options: PointCloudOptions, where: str, episode: Episode, key: str):
    try:
        points, colors = crop_points(
            points, colors, min_bound=options.min_bound, max_bound=options.max_bound
        )
        points, colors = farthest_point_sample(points, options.num_points, colors)
    except ValueError as exc:
        raise RmbFormatError(
            f"{where}: {exc} (box {list(options.min_bound)}..{list(options.max_bound)} after "
            f"rotating by rpy {list(options.rpy_angle)} deg)",
            path=episode.path,
            key=key,
        ) from exc
    cloud = points if colors is None else np.concatenate([points, colors], axis=1)
    return cloud.astype(np.float32)


def camera_pointclouds(
    episode: Episode, camera: str, options: PointCloudOptions, *, progress: bool = True
) -> np.ndarray:
    """The (T, num_points, 6 or 3) float32 clouds of one camera of an (image-resizing) episode."""
    key = K.pointcloud_key(camera)
    rotation = rpy_matrix(options.rpy_angle)
    clouds = []
    bar = tqdm(
        total=len(episode),
        desc=f"{episode.path.name} {camera}",
        unit="step",
        leave=False,
        disable=not progress,
    )
    with bar:
        if key + RAW_SUFFIX in episode:
            raw = np.asarray(episode[key + RAW_SUFFIX][:])
            for step, cloud in enumerate(raw):
                points = cloud[:, :3].astype(np.float64) @ rotation.T
                colors = cloud[:, 3:6] if cloud.shape[1] >= 6 else None
                clouds.append(_sample(points, colors, options, f"step {step}", episode, key))
                bar.update()
            return np.stack(clouds)
        fovy = episode.fovy(camera)
        transform = np.eye(4)
        transform[:3, :3] = rotation
        rgb_series, depth_series = (
            episode[K.rgb_image_key(camera)],
            episode[K.depth_image_key(camera)],
        )
        for start in range(0, len(episode), _CHUNK):
            rgbs = rgb_series[start : start + _CHUNK]
            depths = depth_series[start : start + _CHUNK]
            for offset, (rgb, depth) in enumerate(zip(rgbs, depths, strict=True)):
                try:
                    cloud = depth_to_pointcloud(depth, fovy, rgb, transform=transform)
                except ValueError as exc:
                    raise RmbFormatError(
                        f"step {start + offset}: {exc}", path=episode.path, key=key
                    ) from exc
                clouds.append(
                    _sample(
                        cloud[:, :3], cloud[:, 3:], options, f"step {start + offset}", episode, key
                    )
                )
                bar.update()
    return np.stack(clouds)


def add_pointclouds(
    sources: Iterable[str | Path],
    cameras: Sequence[str],
    options: PointCloudOptions = PointCloudOptions(),
    *,
    overwrite: bool = False,
    progress: bool = True,
) -> list[Path]:
    """Add ``<camera>_pointcloud`` for each camera to every episode of ``sources``.

    Every episode is checked first (readable; images and ``fovy`` present; no existing cloud
    unless ``overwrite``), so a refusal changes nothing. Each episode's HDF5 file is then
    replaced atomically with clouds and attributes added. Returns the episodes changed.
    """
    if not cameras:
        raise ValueError("name at least one camera (--camera NAME)")
    episodes = find_episodes(*sources)
    if not episodes:
        raise RmbFormatError("no episodes (*.rmb, *.hdf5) found", path=", ".join(map(str, sources)))
    for path in episodes:
        with open_episode(path) as episode:
            for camera in cameras:
                _check(episode, camera, overwrite)
    size = tuple(int(v) for v in options.image_size)
    for path in tqdm(episodes, desc="add-pointcloud", unit="episode", disable=not progress):
        with open_episode(path, image_size=size) as episode:
            clouds = {}
            raw = {}
            for camera in cameras:
                key = K.pointcloud_key(camera)
                clouds[key] = camera_pointclouds(episode, camera, options, progress=progress)
                raw[key] = key + RAW_SUFFIX in episode
        with edit_hdf5(path, drop=clouds) as h5:
            for key, data in clouds.items():
                # Fletcher-32 as every dataset the episode writer creates: HDF5 verifies it on
                # every read, so a flipped byte is an error, not a wrong point.
                h5.create_dataset(key, data=data, fletcher32=True)
                h5.attrs[key + "_image_size"] = np.array(
                    [-1, -1] if raw[key] else list(size), dtype=np.int64
                )
                h5.attrs[key + "_min_bound"] = np.asarray(options.min_bound, dtype=np.float64)
                h5.attrs[key + "_max_bound"] = np.asarray(options.max_bound, dtype=np.float64)
                h5.attrs[key + "_rpy_angle"] = np.asarray(options.rpy_angle, dtype=np.float64)
    return episodes
