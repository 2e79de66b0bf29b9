"""Check every source episode before writing anything, and fix what the dataset will hold.

Opening an episode reads only its HDF5 header and video indexes, and low-dimensional data is
small, so every episode is checked up front: the keys named in ``--state-keys``/
``--action-keys``/``--camera-names`` exist, all episodes come from one env at one regular frame
rate (:func:`rmb_lerobot.episode.timing.control_rate`; with ``--fps`` its errors are warnings),
their keys and image sizes agree, their attributes are valid (:mod:`.attrs`) and their values
finite and within float32 (:mod:`.cast`). Each error names the file and the key.

Every episode is opened with :func:`open_source`, which passes ``allow_non_finite`` on to the
reader: by default an episode with NaN/inf in a low-dimensional key or an HDF5 depth image is
refused. With ``--depth``, a camera of ``camera_names`` without the depth images other listed
cameras have is refused too, naming the missing file, unless ``allow_missing_depth`` (then that
camera's depth is left out, with a warning).
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np

from rmb_lerobot import keys as K
from rmb_lerobot.converters.attrs import checked_attrs
from rmb_lerobot.converters.cast import to_float32
from rmb_lerobot.converters.rate import nominal_rate, same_rate
from rmb_lerobot.converters.schema import DatasetSchema, build_schema
from rmb_lerobot.envs.registry import robot_for_env_attr
from rmb_lerobot.episode import Episode, open_episode
from rmb_lerobot.episode import validate as V
from rmb_lerobot.episode.digest import ATTR_VIDEO_SHA256
from rmb_lerobot.episode.timing import control_rate
from rmb_lerobot.errors import MissingKeyError, RmbFormatError

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class ConvertOptions:
    """What to take from the episodes (RMB's training options, plus the frame rate)."""

    state_keys: tuple[str, ...] = (K.MEASURED_JOINT_POS,)
    action_keys: tuple[str, ...] = (K.COMMAND_JOINT_POS,)
    camera_names: tuple[str, ...] | None = None  # None: every camera of the first episode
    depth: bool = False
    task: str | None = None  # None: each episode's task_desc
    fps: str | float | None = None  # None: from the `time` key (else `time` problems only warn)
    skip: int = 1
    allow_non_finite: bool = False  # keep NaN/inf in low-dim keys (stats ignore them)
    allow_missing_depth: bool = False  # --depth: convert cameras whose depth file is missing
    # Every other RMB key (eef poses, velocities, wrench, ...) as its own feature. Off: only
    # state, action and the cameras, which LeRobot's loader reads faster (it materialises every
    # column of each sampled row); from-lerobot then restores only those keys.
    extra_keys: bool = True
    # RGB cameras as LeRobot ``image`` features (PNG in the parquet rows) instead of AV1 videos:
    # the episodes' own frames, losslessly, for ~7x the disk. Not faster to train on with action
    # chunks in LeRobot 0.6.1 (it decodes the PNGs of every row a sample touches: ~1.9x loader CPU
    # at 64x64; benchmarks/RESULTS.md, "Training data path"). Depth stays video.
    image_features: bool = False

    def __post_init__(self) -> None:
        if self.skip < 1:
            raise ValueError(f"skip must be >= 1, got {self.skip}")
        if not self.state_keys or not self.action_keys:
            raise ValueError("at least one state key and one action key are needed")


@dataclass(frozen=True)
class EpisodeSource:
    """One source episode as it will appear in the dataset."""

    path: Path
    length: int  # frames in the dataset (after --skip)
    task: str
    attrs: dict[str, Any] = field(default_factory=dict)
    measured_rate: float | None = None


@dataclass(frozen=True)
class ConversionPlan:
    episodes: tuple[EpisodeSource, ...]
    schema: DatasetSchema
    source_rate: Fraction  # nominal control rate of the episodes
    skip: int
    env: str
    robot_type: str
    allow_non_finite: bool = False
    allow_missing_depth: bool = True  # False: --depth without --allow-missing-depth

    @property
    def rate(self) -> Fraction:
        """Frame rate of the dataset: the source rate divided by ``skip``."""
        return self.source_rate / self.skip

    @property
    def total_frames(self) -> int:
        return sum(ep.length for ep in self.episodes)


def open_source(
    path: str | Path, allow_non_finite: bool = False, allow_missing_depth: bool = True
) -> Episode:
    """Open a source episode the way every step of a conversion must (plan, writers, workers).

    The reader refuses NaN/inf in low-dimensional keys and HDF5 depth unless
    ``allow_non_finite``; the converter checks again where values enter the dataset
    (:mod:`.cast`). Unless ``allow_missing_depth``, a listed camera missing the depth images
    other cameras have is refused (what ``--depth`` needs, see :func:`missing_depth_allowed`).
    """
    return open_episode(
        path, allow_non_finite=allow_non_finite, allow_missing_depth=allow_missing_depth
    )


def missing_depth_allowed(options: ConvertOptions) -> bool:
    """Whether a camera's missing depth file may pass: without ``--depth`` no depth is
    converted, so it does not matter; with it, only ``--allow-missing-depth`` lets it pass."""
    return options.allow_missing_depth or not options.depth


def _warn_missing_depth(episode: Episode, cameras: Sequence[str]) -> None:
    """With ``--depth --allow-missing-depth``: say which listed cameras go without depth."""
    if not episode.path.is_dir():
        return  # single-file episodes have no files to lose
    recorded = episode.video_digests if ATTR_VIDEO_SHA256 in episode.attrs else None
    for key in V.cameras_missing_depth(episode.attrs, episode, recorded):
        if K.camera_of(key) in cameras:
            logger.warning(
                "%s: camera %r has no depth images (expected %s); converted without its depth "
                "(--allow-missing-depth)",
                episode.path,
                K.camera_of(key),
                episode.path / f"{key}.rmb.mp4" if episode.path.is_dir() else repr(key),
            )


def robot_type_of(env: str) -> str:
    """LeRobot's ``robot_type`` for an episode's ``env`` attribute: the robot's short name
    (``ur5e``) when the env registry or the robot records know the attribute exactly
    (:func:`~rmb_lerobot.envs.registry.robot_for_env_attr`), else the attribute itself."""
    robot = robot_for_env_attr(env)
    return robot.name if robot is not None else env


def _require(episode: Episode, key: str, option: str) -> None:
    if key not in episode:
        raise MissingKeyError(
            f"{option} names {key!r}, which this episode lacks; it has: "
            f"{sorted(k for k in episode if not K.is_image_key(k))}",
            path=episode.path,
            key=key,
        )


def _image_shapes(episode: Episode, cameras: Sequence[str], depth: bool) -> dict[str, tuple]:
    shapes = {}
    for camera in cameras:
        for key in K.camera_keys([camera], rgb=True, depth=depth):
            if key in episode:
                shapes[key] = tuple(episode[key].shape[1:3])
    return shapes


def _lowdim_shapes(episode: Episode) -> dict[str, tuple[int, ...]]:
    return {
        key: tuple(episode[key].shape)
        for key in episode
        if not K.is_image_key(key) and not K.is_pointcloud_key(key)
    }


class _Checker:
    """Compares each episode with the first one."""

    def __init__(self, first: Episode, options: ConvertOptions):
        self.first_path = first.path
        self.env = str(first.attrs.get(K.ATTR_ENV, ""))
        self.options = options
        self.cameras = tuple(options.camera_names or first.camera_names)
        for camera in self.cameras:
            if not any(k in first for k in K.camera_keys([camera])):
                raise MissingKeyError(
                    f"--camera-names names {camera!r}, which has no images in this episode; "
                    f"cameras: {first.camera_names}",
                    path=first.path,
                    key=K.rgb_image_key(camera),
                )
        self.rate = self._rate(first, options)
        self.lowdim = _lowdim_shapes(first)
        self.images = _image_shapes(first, self.cameras, options.depth)

    @staticmethod
    def _rate(episode: Episode, options: ConvertOptions) -> float | None:
        """The episode's control rate; with ``--fps`` given, a bad ``time`` only warns."""
        if K.TIME not in episode:
            return None
        time = episode[K.TIME][:]  # the reader refuses NaN/inf here, --fps or not
        try:
            return control_rate(time, path=episode.path)
        except RmbFormatError as exc:
            if options.fps is None:
                error = RmbFormatError(f"{exc}; to convert anyway, pass --fps RATE (the true rate)")
                error.path, error.key = exc.path, exc.key
                raise error from exc
            logger.warning("%s; using --fps %s", exc, options.fps)
            return None

    def check(self, episode: Episode) -> float | None:
        """Raise on any mismatch with the first episode; returns the measured rate."""
        for key in (*self.options.state_keys, *self.options.action_keys):
            option = "--state-keys" if key in self.options.state_keys else "--action-keys"
            _require(episode, key, option)
        env = str(episode.attrs.get(K.ATTR_ENV, ""))
        if env != self.env:
            raise RmbFormatError(
                f"mixed envs in one conversion: {str(self.first_path)!r} is from {self.env!r}, "
                f"this episode from {env!r}; convert each env into its own dataset",
                path=episode.path,
                key=K.ATTR_ENV,
            )
        first = episode.path == self.first_path
        rate = self.rate if first else self._rate(episode, self.options)
        if self.options.fps is not None:
            asserted = float(nominal_rate(str(self.options.fps)))
            if rate is not None and not same_rate(rate, asserted):
                logger.warning(
                    "%s: 'time' gives %s but --fps says %g Hz; using --fps",
                    episode.path,
                    _hz(rate),
                    asserted,
                )
        elif (rate is None) != (self.rate is None) or (rate and not same_rate(rate, self.rate)):
            raise RmbFormatError(
                f"mixed frame rates in one conversion: {str(self.first_path)!r} runs at "
                f"{_hz(self.rate)}, this episode at {_hz(rate)} (from its 'time' key)",
                path=episode.path,
                key=K.TIME,
            )
        shapes = _lowdim_shapes(episode)
        for key, shape in self.lowdim.items():
            if key not in shapes:
                raise MissingKeyError(
                    f"key present in {str(self.first_path)!r} is missing here",
                    path=episode.path,
                    key=key,
                )
            if shapes[key][1:] != shape[1:]:
                raise RmbFormatError(
                    f"shape {shapes[key][1:]} per step differs from {shape[1:]} in "
                    f"{str(self.first_path)!r}",
                    path=episode.path,
                    key=key,
                )
        for key in sorted(set(shapes) - set(self.lowdim)):
            logger.warning("%s: key %r is not in the first episode; not converted", episode, key)
        images = _image_shapes(episode, self.cameras, self.options.depth)
        for key, shape in self.images.items():
            if images.get(key) != shape:
                found = "missing" if key not in images else f"{images[key]}"
                raise RmbFormatError(
                    f"image size {found} differs from {shape} in {str(self.first_path)!r}",
                    path=episode.path,
                    key=key,
                )
        return rate


def _check_values(episode: Episode, keys: Sequence[str], allow_non_finite: bool) -> None:
    """Read the keys to convert now, so bad values fail before anything is written: the reader
    refuses NaN/inf, :func:`.cast.to_float32` values beyond float32 (the writer casts again)."""
    for key in keys:
        values = np.asarray(episode[key][:])
        flat = values.reshape(len(values), -1)
        to_float32(flat, key, path=episode.path, allow_non_finite=allow_non_finite)


def _hz(rate: float | None) -> str:
    return "an unknown rate (no 'time' key)" if rate is None else f"{rate:.6g} Hz"


DEFAULT_STATE_KEYS = ConvertOptions.state_keys
DEFAULT_ACTION_KEYS = ConvertOptions.action_keys


def with_base_velocity(options: ConvertOptions, episode: Episode) -> ConvertOptions:
    """The options with a mobile robot's base velocity added to the default state and action.

    Episodes of a robot on a mobile base record ``measured_mobile_omni_vel`` and
    ``command_mobile_omni_vel`` beside the joints; the default state and action (joints only)
    then also take them, after the joints, so a dataset's vectors are what the env's
    ``agent_pos`` and action hold. Keys given explicitly (not the defaults) are kept as given.
    """
    state, action = options.state_keys, options.action_keys
    if state == DEFAULT_STATE_KEYS and K.MEASURED_MOBILE_OMNI_VEL in episode:
        state = (*state, K.MEASURED_MOBILE_OMNI_VEL)
    if action == DEFAULT_ACTION_KEYS and K.COMMAND_MOBILE_OMNI_VEL in episode:
        action = (*action, K.COMMAND_MOBILE_OMNI_VEL)
    return dataclasses.replace(options, state_keys=state, action_keys=action)


def plan_conversion(paths: Sequence[Path], options: ConvertOptions) -> ConversionPlan:
    """Open and check every episode; raise before anything is written."""
    if not paths:
        raise RmbFormatError("no episodes found (expected *.rmb directories or *.hdf5 files)")
    sources: list[EpisodeSource] = []
    checker: _Checker | None = None
    allow_missing = missing_depth_allowed(options)
    for path in paths:
        with open_source(path, options.allow_non_finite, allow_missing) as episode:
            attrs = checked_attrs(episode.attrs, episode.format.hdf5_path(episode.path))
            if checker is None:
                options = with_base_velocity(options, episode)
                checker = _Checker(episode, options)
            rate = checker.check(episode)
            if options.depth:
                _warn_missing_depth(episode, checker.cameras)
            converted = [k for k in checker.lowdim if not K.is_pointcloud_key(k)]
            _check_values(episode, converted, options.allow_non_finite)
            task = options.task or str(attrs.get(K.ATTR_TASK_DESC) or checker.env)
            length = -(-len(episode) // options.skip)
            sources.append(EpisodeSource(Path(path), length, task, attrs, rate))
    assert checker is not None
    if options.fps is not None:
        source_rate = nominal_rate(str(options.fps))
    elif checker.rate is not None:
        source_rate = nominal_rate(checker.rate)
    else:
        raise MissingKeyError(
            "no 'time' key to measure the frame rate from; pass --fps", path=paths[0], key=K.TIME
        )
    schema = build_schema(
        checker.lowdim,
        checker.images,
        options.state_keys,
        options.action_keys,
        checker.cameras,
        options.depth,
        extra_keys=options.extra_keys,
        image_features=options.image_features,
    )
    return ConversionPlan(
        episodes=tuple(sources),
        schema=schema,
        source_rate=source_rate,
        skip=options.skip,
        env=checker.env,
        robot_type=robot_type_of(checker.env),
        allow_non_finite=options.allow_non_finite,
        allow_missing_depth=allow_missing,
    )
