"""Write RMB episodes step by step, atomically.

The writer streams images to their final encoding as steps arrive (video encoders for the
compact variant, per-frame HDF5 chunks for the single-file variant), so a long episode never
sits in RAM. In the compact variant the encoders run on a background thread
(:class:`~rmb_lerobot.episode.encode_worker.EncodeWorker`, on by default), so a recording loop
renders and steps the next step while the previous frames are encoded; the files are
byte-identical to encoding in the caller's thread. Every HDF5 dataset is stored with HDF5's
Fletcher-32 checksum filter (chunked, no compression: any HDF5 reader, the original RMB's
included, reads it and fails on a damaged chunk instead of returning wrong values), and a
compact episode records the SHA-256 of each of its video files in the ``video_sha256``
attribute (:mod:`rmb_lerobot.episode.digest`).

Everything is written to a hidden temporary sibling (:class:`~rmb_lerobot.staging.Staging`)
and moved into place only when :meth:`EpisodeWriter.close` succeeds: an exception, Ctrl-C or
a crash leaves no episode at the destination, and the temporary of a writer whose process died
is recognised as stale by :func:`~rmb_lerobot.staging.remove_stale` (its lock is free).
Temporaries of older versions of this writer carry no lock; see :func:`remove_legacy_temporaries`.
"""

from __future__ import annotations

import contextlib
import logging
import os
import re
import shlex
import shutil
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from rmb_lerobot import keys as K
from rmb_lerobot.codecs.depth import get_depth_codec, metres_to_mm, mm_to_metres
from rmb_lerobot.codecs.video import RgbVideoWriter
from rmb_lerobot.episode.digest import ATTR_VIDEO_SHA256, format_digests
from rmb_lerobot.episode.encode_worker import DEFAULT_QUEUE_SIZE, EncodeWorker
from rmb_lerobot.episode.layout import EpisodeFormat, episode_format, rgb_video_path
from rmb_lerobot.errors import RmbFormatError
from rmb_lerobot.pose import relative_pose_sequence
from rmb_lerobot.staging import Staging

logger = logging.getLogger(__name__)

ForwardKinematics = Callable[[np.ndarray], np.ndarray]
"""Joint positions (num_joints,) -> end-effector pose(s) (7 * num_eefs,) as (t, qw, qx, qy, qz)."""

# measured/command joint positions -> the eef pose key the FK callable fills in.
_FK_TARGETS = {K.MEASURED_JOINT_POS: K.MEASURED_EEF_POSE, K.COMMAND_JOINT_POS: K.COMMAND_EEF_POSE}


def _encode_attr(value: Any) -> Any:
    """Attribute values as the original RMB stores them (h5py's own conversions)."""
    if isinstance(value, list | tuple) and value and all(isinstance(v, str) for v in value):
        return np.array(value, dtype=h5py.string_dtype())
    if isinstance(value, list | tuple) and not value:
        return np.array([], dtype=np.float64)  # what h5py makes of the original's empty lists
    return value


class EpisodeWriter:
    """Record one episode: ``append`` a dict per step, then ``close`` (or use ``with``).

    Parameters
    ----------
    path:
        ``NAME.rmb`` (compact: HDF5 + MP4 per image stream) or ``NAME.hdf5`` (single file).
    attrs:
        Episode attributes (``env``, ``task_desc``, ``world_idx``, ``demo_name``,
        ``camera_names``, ``<camera>_depth_image_fovy``, ...). ``format`` and ``version`` are
        set by the writer; ``camera_names`` defaults to the cameras seen in the steps.
    fmt:
        ``"rmb"`` or ``"hdf5"``; must agree with the extension (default: from it).
    fk:
        Forward kinematics. When given, ``measured_eef_pose``/``command_eef_pose`` are computed
        from ``measured_joint_pos``/``command_joint_pos`` unless the steps already hold them.
    derive_relative:
        Compute the ``_rel`` keys RMB stores (difference from the previous step; the eef pose
        one is ``prev^-1 * current`` as translation + roll/pitch/yaw) from their absolute keys,
        unless the steps already hold them.
    depth_codec:
        Depth video codec of the compact variant. The default ``rmb-videoio`` is what the
        original RMB reads; others are smaller but only this package reads them.
    background_encoding:
        Compact variant: encode the images on a background thread (same bytes, the caller's
        thread freed for the next step). An encoder's error is raised by the next ``append``
        or by ``close``. The single-file variant always writes in the caller's thread.
    max_queued_images:
        Images waiting for the background encoder at most; ``append`` waits beyond that
        (bounds the memory when the caller is faster than the encoder).
    """

    def __init__(
        self,
        path: str | Path,
        attrs: Mapping[str, Any] | None = None,
        fmt: str | None = None,
        *,
        fk: ForwardKinematics | None = None,
        derive_relative: bool = True,
        depth_codec: str = "rmb-videoio",
        rgb_crf: int = 23,
        rgb_preset: str = "medium",
        overwrite: bool = False,
        background_encoding: bool = True,
        max_queued_images: int = DEFAULT_QUEUE_SIZE,
    ):
        self.path = Path(path)
        self.format = episode_format(self.path)
        if fmt is not None and EpisodeFormat.from_name(fmt) is not self.format:
            raise RmbFormatError(
                f"format {fmt!r} does not match the extension {self.path.suffix!r}", path=self.path
            )
        if self.path.exists() and not overwrite:
            raise RmbFormatError(
                "destination exists (pass overwrite=True to replace it)", path=self.path
            )
        if max_queued_images < 1:
            raise ValueError(f"max_queued_images must be at least 1, got {max_queued_images}")
        self.attrs = dict(attrs or {})
        self.fk = fk
        self.derive_relative = derive_relative
        self._depth_codec = get_depth_codec(depth_codec)
        self._rgb_options = {"crf": rgb_crf, "preset": rgb_preset}
        self.overwrite = overwrite

        self._lowdim: dict[str, list[np.ndarray]] = {}
        self._shapes: dict[str, tuple[tuple[int, ...], np.dtype]] = {}
        self._encoders: dict[str, Any] = {}  # compact: image key -> video writer
        self._video_files: list[Path] = []  # compact: the finished videos, for their digests
        self._h5: h5py.File | None = None  # single file: open from the start for image chunks
        self._worker: EncodeWorker | None = None  # compact + background: runs encoder writes
        self._num_steps = 0
        # The hidden temporary, locked for as long as this process records into it.
        self._staging = Staging(self.path)
        self._tmp = self._staging.path
        try:
            if self.format is EpisodeFormat.COMPACT:
                self._tmp.mkdir()
            else:
                self._h5 = h5py.File(self._tmp, "w")
        except BaseException:
            self._staging.discard()
            raise
        if self.format is EpisodeFormat.COMPACT and background_encoding:
            self._worker = EncodeWorker(max_queued_images, name=f"encode {self.path.name}")
        self._closed = False

    # ------------------------------------------------------------------ recording
    def __len__(self) -> int:
        return self._num_steps

    def append(self, step: Mapping[str, Any]) -> None:
        """Record one step: key -> value (scalars, vectors, images).

        Images are encoded now, or queued for the background encoder (copied, so the caller
        may reuse its buffers).

        Raises:
            RmbFormatError: A bad key, value or shape (nothing of the step is recorded).
            Exception: A background encoder's error from an earlier step.
        """
        if self._closed:
            raise RmbFormatError("writer is closed", path=self.path)
        step = dict(step)
        if self.fk is not None:
            for joint_key, pose_key in _FK_TARGETS.items():
                if joint_key in step and pose_key not in step:
                    step[pose_key] = np.asarray(
                        self.fk(np.asarray(step[joint_key])), dtype=np.float64
                    )
        self._check_keys(step)
        # Validate everything before writing anything, so a bad step leaves no partial step.
        arrays = {key: self._check_value(key, value) for key, value in step.items()}
        for key, array in arrays.items():
            if K.is_image_key(key):
                self._write_image(key, array)
            else:
                self._lowdim.setdefault(key, []).append(array)
        self._num_steps += 1

    def _check_keys(self, step: Mapping[str, Any]) -> None:
        if self._num_steps == 0:
            if K.TIME not in step:
                raise RmbFormatError(
                    f"every step needs {K.TIME!r} (the control rate comes from it)",
                    path=self.path,
                    key=K.TIME,
                )
            return
        expected = set(self._shapes)
        missing, extra = expected - set(step), set(step) - expected
        if missing or extra:
            problem = f"missing {sorted(missing)}" if missing else f"unexpected {sorted(extra)}"
            raise RmbFormatError(
                f"step {self._num_steps} has different keys than step 0: {problem}",
                path=self.path,
                key=sorted(missing or extra)[0],
            )

    def _check_value(self, key: str, value: Any) -> np.ndarray:
        array = np.asarray(value)
        if array.dtype.kind not in "biuf":
            raise RmbFormatError(
                f"expected numbers, got dtype {array.dtype}", path=self.path, key=key
            )
        if K.is_rgb_image_key(key):
            if array.dtype != np.uint8 or array.ndim != 3 or array.shape[2] != 3:
                raise RmbFormatError(
                    f"RGB image must be uint8 (H, W, 3), got {array.dtype} {array.shape}",
                    path=self.path,
                    key=key,
                )
        elif K.is_depth_image_key(key):
            if array.ndim != 2 or array.dtype.kind not in "uf":
                raise RmbFormatError(
                    f"depth image must be (H, W) float metres or uint16 millimetres, got "
                    f"{array.dtype} {array.shape}",
                    path=self.path,
                    key=key,
                )
            if array.dtype.kind == "u" and array.dtype != np.uint16:
                raise RmbFormatError(
                    f"integer depth must be uint16 mm, got {array.dtype}", path=self.path, key=key
                )
        elif key in K.KEYS and K.KEYS[key].quantity is None and array.ndim != 0:
            raise RmbFormatError(
                f"expected a scalar, got shape {array.shape}", path=self.path, key=key
            )
        seen = self._shapes.get(key)
        if seen is None:
            self._shapes[key] = (array.shape, array.dtype)
        elif seen[0] != array.shape:
            raise RmbFormatError(
                f"step {self._num_steps} has shape {array.shape}, earlier steps {seen[0]}",
                path=self.path,
                key=key,
            )
        return array

    def _write_image(self, key: str, image: np.ndarray) -> None:
        if self.format is EpisodeFormat.COMPACT:
            encoder = self._encoders.get(key)
            if encoder is None:
                height, width = image.shape[:2]
                if K.is_rgb_image_key(key):
                    encoder = RgbVideoWriter(
                        rgb_video_path(self._tmp, key), width, height, **self._rgb_options
                    )
                else:
                    target = self._tmp / f"{key}{self._depth_codec.file_suffix}"
                    encoder = self._depth_codec.writer(target, width, height)
                self._encoders[key] = encoder
            if self._worker is None:
                encoder.write(image)
            else:
                self._worker.submit(encoder.write, np.array(image, copy=True))
            return
        if K.is_depth_image_key(key):
            # The single-file variant stores depth as float32 metres, like the original.
            image = mm_to_metres(image) if image.dtype == np.uint16 else image.astype(np.float32)
        dataset = self._h5.get(key)
        if dataset is None:
            dataset = self._h5.create_dataset(
                key,
                shape=(0, *image.shape),
                maxshape=(None, *image.shape),
                dtype=image.dtype,
                chunks=(1, *image.shape),
                fletcher32=True,
            )
        dataset.resize(self._num_steps + 1, axis=0)
        dataset[self._num_steps] = image

    # ------------------------------------------------------------------ finishing
    def _derived_keys(self, data: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        derived = {}
        if not self.derive_relative:
            return derived
        for key in list(data):
            spec = K.KEYS.get(key)
            if spec is None or spec.is_relative or spec.quantity not in K.RELATIVE_QUANTITIES:
                continue
            rel = K.rel_key(key)
            if rel in data:
                continue
            values = data[key]
            if spec.quantity is K.Quantity.EEF_POSE:
                poses = values.reshape(len(values), -1, 7)
                rels = np.stack(
                    [relative_pose_sequence(poses[:, i]) for i in range(poses.shape[1])], 1
                )
                derived[rel] = rels.reshape(len(values), -1)
            else:
                diff = np.zeros_like(values)
                diff[1:] = values[1:] - values[:-1]
                derived[rel] = diff
        return derived

    def _final_attrs(self) -> dict[str, Any]:
        attrs = {
            K.ATTR_DEMO_NAME: "",
            K.ATTR_TASK_DESC: "",
            K.ATTR_ENV: "",
            K.ATTR_WORLD_IDX: 0,
            K.ATTR_RGB_TACTILE_NAMES: [],
            K.ATTR_POINTCLOUD_CAMERA_NAMES: [],
        }
        cameras = list(dict.fromkeys(K.camera_of(k) for k in self._shapes if K.is_image_key(k)))
        attrs[K.ATTR_CAMERA_NAMES] = cameras
        attrs.update(self.attrs)
        attrs.pop(ATTR_VIDEO_SHA256, None)  # another episode's digests (copied attributes)
        if self.format is EpisodeFormat.COMPACT:
            attrs[ATTR_VIDEO_SHA256] = format_digests(self._video_files)
        attrs[K.ATTR_VERSION] = self.attrs.get(K.ATTR_VERSION, K.RMB_FORMAT_VERSION)
        attrs[K.ATTR_FORMAT] = self.format.value
        for camera in cameras:
            if K.depth_image_key(camera) in self._shapes and K.fovy_attr(camera) not in attrs:
                logger.warning(
                    "%s: no %s attribute; point clouds need it", self.path, K.fovy_attr(camera)
                )
        return attrs

    def close(self) -> Path:
        """Finish encoding, write the low-dimensional data and attributes, move into place."""
        if self._closed:
            return self.path
        if self._num_steps == 0:
            self.abort()
            raise RmbFormatError("no steps were appended; nothing written", path=self.path)
        try:
            if self._worker is not None:
                self._worker.finish()  # every queued frame encoded (or its error raised)
                self._worker = None
            for encoder in self._encoders.values():
                encoder.close()
            self._video_files = [Path(encoder.path) for encoder in self._encoders.values()]
            self._encoders.clear()
            data = {key: np.stack(values) for key, values in self._lowdim.items()}
            data.update(self._derived_keys(data))
            h5 = (
                self._h5
                if self._h5 is not None
                else h5py.File(self._tmp / K.COMPACT_MAIN_FILE, "w")
            )
            with h5:
                for key, values in data.items():
                    h5.create_dataset(key, data=values, fletcher32=True)
                for name, value in self._final_attrs().items():
                    h5.attrs[name] = _encode_attr(value)
            self._h5 = None
            self._move_into_place()
        except BaseException:
            self.abort()
            raise
        self._closed = True
        logger.info("wrote %s (%d steps)", self.path, self._num_steps)
        return self.path

    def _move_into_place(self) -> None:
        if self.path.exists() and not self.overwrite:
            raise RmbFormatError(
                "destination appeared while recording; not overwriting", path=self.path
            )
        # With overwrite, an atomic exchange: readers see the old episode or the new one.
        self._staging.commit(overwrite=self.overwrite)

    def abort(self) -> None:
        """Discard everything written so far; nothing appears at ``path``."""
        if self._worker is not None:
            self._worker.cancel()  # queued frames are dropped; the thread is joined
            self._worker = None
        for encoder in self._encoders.values():
            with contextlib.suppress(Exception):
                encoder.close()
        self._encoders.clear()
        if self._h5 is not None:
            with contextlib.suppress(Exception):
                self._h5.close()
            self._h5 = None
        self._staging.discard()
        self._closed = True

    def __enter__(self) -> EpisodeWriter:
        return self

    def __del__(self) -> None:
        # A writer dropped unclosed can never be committed: free its temporary and lock now
        # rather than at process exit.
        if not getattr(self, "_closed", True):
            with contextlib.suppress(Exception):
                self.abort()

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.close()
        else:
            self.abort()


LEGACY_MAX_AGE_S = 24 * 3600
"""Legacy temporaries untouched this long are removed; younger ones are only reported."""

# What versions before the flock'ed staging left: ``.NAME.rmb.tmp-<8 hex>`` (the episode being
# written) and ``.NAME.rmb.old-<8 hex>`` (the previous episode while being overwritten).
_LEGACY = re.compile(r"\.(?P<name>.+\.(?:rmb|hdf5))\.(?P<kind>tmp|old)-[0-9a-f]{8}", re.IGNORECASE)


def remove_legacy_temporaries(
    directory: str | Path, max_age_s: float = LEGACY_MAX_AGE_S
) -> tuple[list[Path], list[Path]]:
    """Remove episode temporaries of older versions, which carry no lock; returns (removed, kept).

    Without a lock nothing tells a dead writer's temporary from one a still-running older
    version is writing, so age decides: such a writer modifies its temporary at every step and
    an episode takes minutes, hence one untouched for ``max_age_s`` (a day) is dead unless its
    process was stopped for that long. Younger ones are kept and reported with the command that
    deletes them. A ``.old-`` sibling whose episode is missing holds the only copy of that
    episode (the old writer died between two renames): it is never removed, and reported with
    the command that restores it.
    """
    directory = Path(directory)
    removed: list[Path] = []
    kept: list[Path] = []
    if not directory.is_dir():
        return removed, kept
    now = time.time()
    orphans: list[tuple[Path, Path]] = []
    for entry in sorted(directory.iterdir()):
        match = _LEGACY.fullmatch(entry.name)
        if match is None:
            continue
        dest = directory / match["name"]
        if match["kind"] == "old" and not dest.exists():
            orphans.append((entry, dest))
        elif now - _newest_mtime(entry) >= max_age_s:
            _remove(entry)
            removed.append(entry)
        else:
            kept.append(entry)
    if removed:
        logger.warning(
            "removed %d temporar%s of an older rmb_lerobot version, untouched for over %.0f h, "
            "in %s: %s",
            len(removed),
            "y" if len(removed) == 1 else "ies",
            max_age_s / 3600,
            directory,
            ", ".join(p.name for p in removed),
        )
    if kept:
        logger.warning(
            "%d temporar%s of an older rmb_lerobot version in %s (no lock says whether its "
            "writer still runs; removed once untouched for %.0f h). If no older version is "
            "writing there, delete now with: rm -rf -- %s",
            len(kept),
            "y" if len(kept) == 1 else "ies",
            directory,
            max_age_s / 3600,
            " ".join(shlex.quote(str(p)) for p in kept),
        )
    for entry, dest in orphans:
        logger.warning(
            "%s holds the previous version of the missing episode %s (an older rmb_lerobot "
            "stopped while overwriting it); restore it with: mv -n -- %s %s",
            entry,
            dest.name,
            shlex.quote(str(entry)),
            shlex.quote(str(dest)),
        )
    return removed, kept + [entry for entry, _ in orphans]


def _newest_mtime(path: Path) -> float:
    """Latest modification time in a file or directory tree (what a live writer keeps fresh)."""
    newest = path.lstat().st_mtime
    if path.is_dir() and not path.is_symlink():
        for root, dirs, files in os.walk(path):
            for name in dirs + files:
                with contextlib.suppress(FileNotFoundError):
                    newest = max(newest, os.lstat(os.path.join(root, name)).st_mtime)
    return newest


def _remove(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        with contextlib.suppress(FileNotFoundError):
            path.unlink()


# Depth given as metres is rounded to millimetres by the video codecs; re-exported for users.
__all__ = [
    "LEGACY_MAX_AGE_S",
    "EpisodeWriter",
    "ForwardKinematics",
    "metres_to_mm",
    "remove_legacy_temporaries",
]
