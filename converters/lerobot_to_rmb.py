"""A local LeRobotDataset v3 -> RMB episodes (what ``rmb-convert from-lerobot`` runs).

Works on datasets written by ``rmb-convert to-lerobot`` (restoring every key and attribute from
``meta/rmb.json``) and on any other LeRobot dataset, e.g. one recorded with ``lerobot-record``,
through the documented mapping of :mod:`.lerobot_mapping`. Episodes are written with
:class:`~rmb_lerobot.episode.EpisodeWriter` (missing ``_rel`` keys are derived as the original
recorder does) into an output directory that appears only when every episode is written
(:mod:`.atomic`: built in a locked hidden sibling, what interrupted runs left there is removed
first). Non-finite numbers in the dataset are refused unless ``allow_non_finite``, as in
``to-lerobot``.
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from lerobot.datasets.lerobot_dataset import LeRobotDataset

from rmb_lerobot import keys as K
from rmb_lerobot import lerobot_names as N
from rmb_lerobot.converters.atomic import prepare_destination, staged_output
from rmb_lerobot.converters.attrs import checked_attrs
from rmb_lerobot.converters.lerobot_frames import CHUNK, image_column_frames, iter_video_frames
from rmb_lerobot.converters.lerobot_mapping import (
    KeyDims,
    KeyMapping,
    MappingOverrides,
    resolve_mapping,
)
from rmb_lerobot.converters.metadata import read_rmb_metadata
from rmb_lerobot.converters.progress import Bars
from rmb_lerobot.converters.schema import uses_policy_view
from rmb_lerobot.episode import EpisodeFormat, EpisodeWriter
from rmb_lerobot.episode.validate import check_names_have_images
from rmb_lerobot.errors import MissingKeyError, RmbFormatError
from rmb_lerobot.pose import POLICY_POSE_DIM, policy_to_pose

_TIMESTAMP = "timestamp"
_EPISODE_INDEX = "episode_index"
_INFO_FILE = "meta/info.json"
DEFAULT_ENV = "LeRobot"  # ``env`` attribute of episodes from datasets without a robot_type


def open_dataset(repo_id: str | None, root: str | Path | None) -> LeRobotDataset:
    """The dataset at ``root`` (never downloaded), else ``repo_id`` as LeRobot resolves it.

    ``repo_id`` is read from ``$HF_LEROBOT_HOME/REPO_ID`` if it is there, and otherwise
    downloaded from the Hub into it, except with ``HF_HUB_OFFLINE`` set.

    Args:
        repo_id: The dataset's id (``namespace/name``).
        root: The dataset's directory, or None for ``$HF_LEROBOT_HOME/REPO_ID``.

    Returns:
        The dataset.

    Raises:
        RmbFormatError: ``root`` (or, offline, ``$HF_LEROBOT_HOME/REPO_ID``) holds no dataset.
        ValueError: Neither ``repo_id`` nor ``root`` is given.
    """
    if root is not None:
        root = Path(root)
        if not (root / _INFO_FILE).is_file():
            raise RmbFormatError(f"no LeRobotDataset here ({_INFO_FILE} missing)", path=root)
        return LeRobotDataset(repo_id or f"local/{root.name}", root=root, video_backend="pyav")
    if repo_id is None:
        raise ValueError("give a REPO_ID or --root DIR")
    local = _lerobot_home() / repo_id
    if not (local / _INFO_FILE).is_file() and _hub_offline():
        raise RmbFormatError(
            f"dataset {repo_id} is not in $HF_LEROBOT_HOME and HF_HUB_OFFLINE is set, so it is "
            "not downloaded from the Hub; unset HF_HUB_OFFLINE to download it, or give its "
            "directory with --root",
            path=local,
        )
    return LeRobotDataset(repo_id, video_backend="pyav")


def _lerobot_home() -> Path:
    """``$HF_LEROBOT_HOME`` as LeRobot resolves it (read when LeRobot is imported)."""
    from lerobot.utils.constants import HF_LEROBOT_HOME

    return Path(HF_LEROBOT_HOME)


def _hub_offline() -> bool:
    """Whether ``HF_HUB_OFFLINE`` is set now (huggingface_hub reads it at import only)."""
    from huggingface_hub import constants

    value = os.environ.get("HF_HUB_OFFLINE", "").strip().upper()
    return constants.HF_HUB_OFFLINE or value in {"1", "ON", "YES", "TRUE"}


def _split_vector(
    values: np.ndarray, parts: KeyDims, feature: str, have: Mapping[str, np.ndarray], root: Path
) -> dict[str, np.ndarray]:
    """Cut a state/action vector ``(T, D)`` into RMB keys; policy-view eef poses back to poses."""
    out: dict[str, np.ndarray] = {}
    offset, width = 0, values.shape[1]
    for key, dim in parts:
        size = width - offset if dim is None else dim
        part = values[:, offset : offset + size]
        offset += size
        if key in have:  # kept raw as its own feature: exact, unlike the policy view
            continue
        if uses_policy_view(key):
            poses = policy_to_pose(part.reshape(len(part), -1, POLICY_POSE_DIM))
            part = poses.reshape(len(part), -1)
        out[key] = part
    if offset != width:
        raise RmbFormatError(
            f"{feature!r} has {width} numbers but the mapping {list(parts)} covers {offset}; "
            "give the sizes as KEY:DIM",
            path=root,
            key=feature,
        )
    return out


def _check_finite(
    rows: Mapping[str, np.ndarray], features: Sequence[str], index: int, root: Path
) -> None:
    """Refuse NaN/inf in the numeric features of one episode (rows of the dataset)."""
    for feature in features:
        values = np.asarray(rows[feature])
        if values.dtype.kind not in "fc":
            continue
        bad = ~np.isfinite(values.reshape(len(values), -1))
        if bad.any():
            frame, component = (int(i) for i in np.argwhere(bad)[0])
            value = values.reshape(len(values), -1)[frame, component]
            raise RmbFormatError(
                f"{value} in episode {index}, frame {frame}, component {component} "
                f"({int(bad.sum())} non-finite values in this episode); expected finite numbers "
                "(pass --allow-non-finite to keep NaN/inf)",
                path=root,
                key=feature,
            )


def _lowdim(
    rows: Mapping[str, np.ndarray], mapping: KeyMapping, root: Path
) -> dict[str, np.ndarray]:
    """Every low-dimensional RMB key of one episode, as float64 ``(T, d)`` (RMB's dtype)."""
    data = {
        key: np.asarray(rows[feature], dtype=np.float64).reshape(len(rows[feature]), -1)
        for feature, key in mapping.features.items()
    }
    for feature, parts in ((N.STATE, mapping.state), (N.ACTION_KEY, mapping.action)):
        if feature in rows:
            vector = np.asarray(rows[feature], dtype=np.float64)
            vector = vector.reshape(len(vector), -1)
            data.update(_split_vector(vector, parts, feature, data, root))
    if K.TIME not in data:
        data[K.TIME] = np.asarray(rows[_TIMESTAMP], dtype=np.float64).reshape(-1, 1)
    return data


def _step_value(key: str, values: np.ndarray, i: int) -> Any:
    if K.is_tactile_key(key) and values.shape[1] == np.prod(K.TACTILE_SHAPE):
        return values[i].reshape(K.TACTILE_SHAPE)  # RMB stores each grid as (rows, cols)
    spec = K.KEYS.get(key)
    return values[i, 0] if spec is not None and spec.quantity is None else values[i]


def _safe_name(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", name).strip("._") or "episode"


class _EpisodeAttrs:
    """RMB attributes per episode: from ``meta/rmb.json`` when present, else built.

    Camera name lists keep only cameras whose images the episode gets (a dataset converted
    with ``--camera-names`` lacks the others): RMB lists a camera only if it recorded it.
    """

    def __init__(self, dataset: LeRobotDataset, rmb_meta: Mapping | None, mapping: KeyMapping):
        self._dataset = dataset
        self._mapping = mapping
        self._stored = {ep["episode_index"]: ep for ep in (rmb_meta or {}).get("episodes", [])}

    def __call__(self, index: int) -> dict[str, Any]:
        attrs = self._attrs(index)
        present = set(self._mapping.images.values())
        for attr, camera, _ in check_names_have_images(attrs, present):
            attrs[attr] = [name for name in attrs[attr] if name != camera]
        return attrs

    def _attrs(self, index: int) -> dict[str, Any]:
        stored = self._stored.get(index)
        if stored is not None:
            attrs = checked_attrs(stored["attrs"], self._dataset.root / N.RMB_METADATA_PATH)
            return {k: v for k, v in attrs.items() if k != K.ATTR_FORMAT}
        tasks = self._dataset.meta.episodes[index]["tasks"]
        return {
            K.ATTR_DEMO_NAME: f"episode_{index:06d}",
            K.ATTR_TASK_DESC: str(tasks[0]) if len(tasks) else "",
            K.ATTR_ENV: self._dataset.meta.robot_type or DEFAULT_ENV,
            K.ATTR_WORLD_IDX: 0,
            K.ATTR_CAMERA_NAMES: self._mapping.cameras(),
        }


def _image_chunks(
    dataset: LeRobotDataset, index: int, feature: str, rows: Mapping
) -> Iterator[np.ndarray]:
    """Frames of an image feature in chunks of :data:`CHUNK` (videos decoded, images read)."""
    if feature in dataset.meta.video_keys:
        return iter_video_frames(dataset, index, feature, rows[_TIMESTAMP])
    images = rows[feature]
    return (image_column_frames(images[i : i + CHUNK]) for i in range(0, len(images), CHUNK))


def _write_episode(
    dataset: LeRobotDataset,
    index: int,
    rows: Mapping[str, np.ndarray],
    mapping: KeyMapping,
    attrs: dict[str, Any],
    path: Path,
    bars: Bars,
    allow_non_finite: bool,
) -> None:
    if not allow_non_finite:
        numeric = [*mapping.features, N.STATE, N.ACTION_KEY, _TIMESTAMP]
        _check_finite(rows, [f for f in numeric if f in rows], index, dataset.root)
    lowdim = _lowdim(rows, mapping, dataset.root)
    length = len(rows[_TIMESTAMP])
    streams = {
        key: _image_chunks(dataset, index, feature, rows) for feature, key in mapping.images.items()
    }
    with EpisodeWriter(path, attrs) as writer:
        for first in range(0, length, CHUNK):
            frames = {key: next(stream) for key, stream in streams.items()}
            for i in range(first, min(length, first + CHUNK)):
                step = {key: _step_value(key, values, i) for key, values in lowdim.items()}
                step.update({key: chunk[i - first] for key, chunk in frames.items()})
                writer.append(step)
            bars.frames(min(CHUNK, length - first))
    bars.episode_done()


def from_lerobot(
    repo_id: str | None = None,
    *,
    root: str | Path | None = None,
    output: str | Path,
    fmt: str = "rmb",
    episodes: Sequence[int] | None = None,
    overrides: MappingOverrides | None = None,
    overwrite: bool = False,
    progress: bool = True,
    allow_non_finite: bool = False,
) -> list[Path]:
    """Write episodes of a LeRobotDataset as RMB episodes under ``output``; returns their paths.

    NaN/inf in the dataset's numeric features fail the conversion (naming the feature, episode
    and frame) unless ``allow_non_finite``.
    """
    output = prepare_destination(Path(output).expanduser().absolute(), overwrite)
    suffix = "." + EpisodeFormat.from_name(fmt).short_name
    dataset = open_dataset(repo_id, root)
    meta = dataset.meta
    selected = list(range(meta.total_episodes)) if episodes is None else list(episodes)
    bad = [i for i in selected if not 0 <= i < meta.total_episodes]
    if bad:
        raise MissingKeyError(
            f"episodes {bad} not in the dataset (it has {meta.total_episodes})",
            path=dataset.root,
            key=_EPISODE_INDEX,
        )
    rmb_meta = read_rmb_metadata(dataset.root)
    mapping = resolve_mapping(meta.features, meta.depth_keys, rmb_meta, overrides)
    attrs_of = _EpisodeAttrs(dataset, rmb_meta, mapping)
    table = dataset.hf_dataset.with_format("numpy")
    episode_column = np.asarray(table[_EPISODE_INDEX])
    written, names = [], set()
    lengths = [meta.episodes[i]["length"] for i in selected]
    with (
        staged_output(output, overwrite) as staging,
        Bars(len(selected), sum(lengths), enabled=progress) as bars,
    ):
        tmp = staging.path
        tmp.mkdir()
        for index in selected:
            rows_at = np.flatnonzero(episode_column == index)
            rows = table[int(rows_at[0]) : int(rows_at[-1]) + 1]
            attrs = attrs_of(index)
            name = _safe_name(str(attrs.get(K.ATTR_DEMO_NAME) or f"episode_{index:06d}"))
            name = name if name not in names else f"{name}_{index:06d}"
            names.add(name)
            path = tmp / f"{name}{suffix}"
            _write_episode(dataset, index, rows, mapping, attrs, path, bars, allow_non_finite)
            written.append(output / f"{name}{suffix}")
    return written
