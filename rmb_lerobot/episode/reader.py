"""Read RMB episodes (``NAME.rmb/`` compact directories and ``NAME.hdf5`` single files).

Everything is read lazily: opening an episode parses only the HDF5 header (a video's packet
index is read when its key is first used); low-dimensional keys are read on indexing and video
frames are decoded by random access (seek to the nearest key frame), never the whole video for
one sample as the original loader does.

Bad data is an :class:`RmbFormatError` (or :class:`MissingKeyError`) naming the file, the key
and the value. At open, from metadata only: attributes (UTF-8 text, name lists), flat layout,
dtype and shape of every key against the catalogue and the robot the ``env`` attribute names
(:mod:`rmb_lerobot.episode.validate`), and RGB images for every listed camera. On read:
non-finite low-dimensional values (unless ``allow_non_finite=True``), step counts, and
corrupt video (:class:`rmb_lerobot.codecs.video.VideoFrameReader`). :meth:`Episode.validate`
checks everything but the decoding of every frame, cheaply (``frames=True`` adds it).

What stays undetectable in videos: RMB's MP4s carry no checksums, so damage that leaves a
syntactically valid H.264 stream decodes to wrong frames without any error. Byte flips in
the slice data of lossy RGB (a residual coefficient, a motion vector, a quantiser) and of
the lossless videoio depth (whose error then stays in the Y/V planes, metres off where the
high byte is hit), and flips in the codec parameters in the ``avcC`` box (e.g. the initial
quantiser) are of that kind. Flips in bytes no decoder reads (metadata, the encoder's
settings string) change nothing. ``rmbz`` depth files checksum every byte. Episodes this
package writes record each video's SHA-256 (``video_sha256``), checked on demand
(``verify=True``, ``rmb-data verify``), and store every HDF5 dataset with HDF5's Fletcher-32
filter, which HDF5 checks on every read: a flipped byte in their data is an error, where in a
file of the original RMB (no checksums) it silently changes a value or an image.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import cv2
import h5py
import numpy as np

from rmb_lerobot import keys as K
from rmb_lerobot.codecs.depth import DEPTH_CODECS, find_depth_file, mm_to_metres
from rmb_lerobot.codecs.video import RgbVideoReader
from rmb_lerobot.episode import validate as V
from rmb_lerobot.episode.digest import ATTR_VIDEO_SHA256, check_digests, parse_digests
from rmb_lerobot.episode.layout import (
    RGB_VIDEO_SUFFIX,
    EpisodeFormat,
    episode_format,
    rgb_video_path,
)
from rmb_lerobot.episode.timing import control_rate
from rmb_lerobot.errors import MissingKeyError, RmbFormatError

logger = logging.getLogger(__name__)

Index = int | slice | list[int] | np.ndarray


class H5Series:
    """A lazily read HDF5 dataset: ``series[i]``/``series[a:b]`` read only what is asked.

    ``check(data, index)`` (if given) inspects every read before ``transform``.
    """

    def __init__(self, dataset: h5py.Dataset, path: Path, transform=None, check=None):
        self._dataset = dataset
        self._path = path
        self._transform = transform
        self._check = check

    def __len__(self) -> int:
        return self._dataset.shape[0]

    @property
    def shape(self) -> tuple[int, ...]:
        return self._dataset.shape

    @property
    def dtype(self) -> np.dtype:
        return self._dataset.dtype

    def __getitem__(self, index: Index) -> np.ndarray:
        if isinstance(index, list | np.ndarray):
            # h5py needs increasing fancy indices; read sorted unique and scatter back.
            idx = np.asarray(index, dtype=np.int64) % len(self)
            uniq, inverse = np.unique(idx, return_inverse=True)
            data = self._read(uniq.tolist())[inverse]
        else:
            data = self._read(index)
        if self._check is not None:
            self._check(data, index)
        return data if self._transform is None else self._transform(data)

    def _read(self, index) -> np.ndarray:
        try:
            return np.asarray(self._dataset[index])
        except (OSError, RuntimeError, KeyError) as exc:
            raise RmbFormatError(
                f"cannot read data (corrupt or truncated HDF5?): {exc}",
                path=self._path,
                key=self._dataset.name.lstrip("/"),
            ) from exc

    def __array__(self, dtype=None, copy=None) -> np.ndarray:
        data = self[:]
        return data if dtype is None else data.astype(dtype)


class VideoSeries:
    """Frames of one image key stored as video; decoded by random access."""

    def __init__(self, reader, transform=None):
        self._reader = reader
        self._transform = transform

    def __len__(self) -> int:
        return len(self._reader)

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(self._reader.shape)

    def __getitem__(self, index: Index) -> np.ndarray:
        data = self._reader[index]
        return data if self._transform is None else self._transform(data)

    def __array__(self, dtype=None, copy=None) -> np.ndarray:
        data = self[:]
        return data if dtype is None else data.astype(dtype)

    def close(self) -> None:
        self._reader.close()


def _resize(images: np.ndarray, image_size: tuple[int, int], interpolation: int) -> np.ndarray:
    """Resize (H, W[, C]) or (N, H, W[, C]) images to ``image_size = (width, height)``."""
    single = images.ndim == 2 or (
        images.ndim == 3 and images.shape[-1] == 3 and images.dtype == np.uint8
    )
    frames = [images] if single else list(images)
    out = [cv2.resize(f, image_size, interpolation=interpolation) for f in frames]
    return out[0] if single else np.stack(out) if out else images


class Episode:
    """One RMB episode. Use :func:`open_episode`; close it (or use ``with``) when done.

    ``ep.keys()`` lists every key; ``len(ep)`` is the number of steps; ``ep[key]`` returns a
    lazily read series (``ep["time"][:]``, ``ep["front_rgb_image"][i]`` -> uint8 HxWx3,
    ``ep["front_depth_image"][a:b]`` -> float32 metres NxHxW). With ``cache=True`` every
    ``ep[key]`` is loaded once into RAM and returned as a numpy array (RMB's option to load the
    whole dataset into memory).

    Low-dimensional float keys holding NaN or +-inf raise :class:`RmbFormatError` when read
    (naming the first such step), unless ``allow_non_finite=True``: RMB data is finite (its
    real envs refuse non-finite commands), so such values mean a broken sensor or writer.
    HDF5 depth images holding NaN or +-inf are refused the same way (naming the frame and
    counting the pixels); depth videos cannot hold them. Zero and negative depths mean "no
    data" and are returned as stored. Point clouds are not checked.

    Cameras: every name in ``camera_names``, ``rgb_tactile_names`` and
    ``pointcloud_camera_names`` needs RGB images, every point-cloud camera depth, and when any
    camera of ``camera_names`` has depth, all of them must (``allow_missing_depth=True``
    reads such an episode without the missing depth). ``verify=True`` compares the video
    files with the SHA-256 digests the writer recorded (:meth:`verify_digests`).
    """

    def __init__(
        self,
        path: str | Path,
        *,
        image_size: tuple[int, int] | None = None,
        cache: bool = False,
        depth_interpolation: int = cv2.INTER_NEAREST,
        allow_non_finite: bool = False,
        allow_missing_depth: bool = False,
        verify: bool = False,
    ):
        self.path = Path(path)
        self.format = episode_format(self.path)
        self.image_size = None if image_size is None else (int(image_size[0]), int(image_size[1]))
        self.cache = cache
        self.allow_non_finite = allow_non_finite
        self.allow_missing_depth = allow_missing_depth
        self._depth_interpolation = depth_interpolation
        self._cached: dict[str, np.ndarray] = {}
        self._open_series: list[VideoSeries] = []
        self._h5_path = self.format.hdf5_path(self.path)
        if not self._h5_path.is_file():
            raise RmbFormatError(
                f"episode not found: expected {self.format.describe()}", path=self._h5_path
            )
        try:
            self._h5 = h5py.File(self._h5_path, "r")
        except V.H5_ERRORS as exc:
            raise RmbFormatError(
                f"cannot open HDF5 file (truncated or corrupt?): {exc}", path=self._h5_path
            ) from exc
        try:
            self._open()
            if verify:
                self.verify_digests()
        except BaseException:
            self._h5.close()
            raise

    def _open(self) -> None:
        """Read and check the header (no data): attributes, keys, dtypes, shapes, cameras."""
        self.attrs: dict[str, Any] = V.read_attrs(self._h5, self._h5_path)
        self._h5_ids, specs = V.datasets(self._h5, self._h5_path)
        self._h5_names = list(self._h5_ids)
        self._h5_datasets: dict[str, h5py.Dataset] = {}  # made on first use
        V.check_datasets(specs, self._h5_path, self.attrs.get(K.ATTR_ENV))
        self._video_keys = self._scan_video_keys()
        self._check_listed_cameras()
        self._length = self._infer_length()

    # ------------------------------------------------------------------ metadata
    def _scan_video_keys(self) -> dict[str, Path]:
        if self.format is not EpisodeFormat.COMPACT:
            return {}
        found = {}
        for entry in sorted(self.path.iterdir()):
            key = entry.name.removesuffix(RGB_VIDEO_SUFFIX)
            if entry.name.endswith(RGB_VIDEO_SUFFIX) and K.is_rgb_image_key(key):
                found[key] = entry
        for camera_key in self._depth_keys_on_disk():
            hit = find_depth_file(self.path, camera_key)
            if hit is not None:
                found[camera_key] = hit[0]
        return found

    def _depth_keys_on_disk(self) -> list[str]:
        names = set()
        for entry in self.path.iterdir():
            stem = entry.name.split(".", 1)[0]
            if K.is_depth_image_key(stem):
                names.add(stem)
        return sorted(names)

    def _check_listed_cameras(self) -> None:
        """Every camera the attributes list must have its images (see validate)."""
        missing = V.check_names_have_images(self.attrs, self)
        if not missing and not self.allow_missing_depth and self.format is EpisodeFormat.COMPACT:
            recorded = self.video_digests if ATTR_VIDEO_SHA256 in self.attrs else None
            missing = [
                (K.ATTR_CAMERA_NAMES, K.camera_of(key), key)
                for key in V.cameras_missing_depth(self.attrs, self, recorded)
            ]
        if not missing:
            return
        attr, camera, key = missing[0]
        kind = "RGB" if K.is_rgb_image_key(key) else "depth"
        if self.format is EpisodeFormat.COMPACT:
            if K.is_rgb_image_key(key):
                expected = rgb_video_path(self.path, key)
            else:
                expected = self.path / f"{key}{next(iter(DEPTH_CODECS.values())).file_suffix}"
            where = f"expected {str(expected)!r} (or a dataset {key!r} in {K.COMPACT_MAIN_FILE})"
        else:
            expected = self._h5_path
            where = f"expected a dataset {key!r} in this file"
        others = ""
        if attr == K.ATTR_CAMERA_NAMES and not K.is_rgb_image_key(key):
            others = (
                " (the file was recorded, or other listed cameras have depth; to go on without "
                "this camera's depth: allow_missing_depth=True, --allow-missing-depth)"
            )
        raise MissingKeyError(
            f"camera {camera!r} is listed in the {attr!r} attribute but has no {kind} images: "
            f"{where}{others}",
            path=expected,
            key=key,
        )

    def _infer_length(self) -> int:
        if K.TIME in self._h5_ids:
            return int(self._h5_ids[K.TIME].shape[0])
        for dataset in self._h5_ids.values():
            return int(dataset.shape[0])
        for key in self._video_keys:
            with self._open_video(key) as reader:
                return len(reader)
        return 0

    def keys(self) -> list[str]:
        """Every key of the episode: HDF5 datasets first, then video-backed image keys."""
        return [*self._h5_names, *self._video_keys]

    def __contains__(self, key: object) -> bool:
        return key in self._h5_ids or key in self._video_keys

    def __iter__(self) -> Iterator[str]:
        return iter(self.keys())

    def __len__(self) -> int:
        return self._length

    @property
    def camera_names(self) -> list[str]:
        """Cameras with image data, in the order of the ``camera_names`` attribute if present."""
        present = {K.camera_of(k) for k in self.keys() if K.is_image_key(k)}
        ordered = [c for c in self.attrs.get(K.ATTR_CAMERA_NAMES, []) if c in present]
        return ordered + sorted(present - set(ordered))

    def fovy(self, camera: str) -> float:
        """Vertical field of view (degrees) of a depth camera, from the file attributes."""
        name = K.fovy_attr(camera)
        if name not in self.attrs:
            raise MissingKeyError("attribute missing", path=self._h5_path, key=name)
        value = self.attrs[name]
        try:
            fovy = float(value)
        except (TypeError, ValueError):
            fovy = float("nan")
        if not 0 < fovy < 180:
            raise RmbFormatError(
                f"attribute holds {value!r}; expected a field of view in degrees, 0 < fovy < 180",
                path=self._h5_path,
                key=name,
            )
        return fovy

    @property
    def fps(self) -> float:
        """Control rate (Hz) from the ``time`` key (never from the videos, which carry none).

        The mean rate over the episode, after :func:`rmb_lerobot.episode.timing.control_rate`
        checked that ``time`` is regular (every step at most 3 times the median step) and
        plausible (1 to 1000 Hz).
        """
        return control_rate(self[K.TIME][:], path=self._h5_path, key=K.TIME)

    # ------------------------------------------------------------------ data
    def __getitem__(self, key: str):
        if self.cache:
            if key not in self._cached:
                self._cached[key] = np.asarray(self._series(key)[:])
            return self._cached[key]
        return self._series(key)

    def _series(self, key: str):
        if key in self._video_keys:
            return self._video_series(key)
        if key not in self._h5_ids:
            raise MissingKeyError(
                f"key not in episode; available: {self.keys()}", path=self.path, key=key
            )
        dataset = self._h5_datasets.get(key)
        if dataset is None:
            dataset = self._h5_datasets[key] = h5py.Dataset(self._h5_ids[key])
        if dataset.shape[0] != self._length:
            raise RmbFormatError(
                f"has {dataset.shape[0]} steps but the episode has {self._length}",
                path=self._h5_path,
                key=key,
            )
        if K.is_rgb_image_key(key) and self.image_size:
            return H5Series(dataset, self._h5_path, self._rgb_transform)
        if K.is_depth_image_key(key):
            depth_check = None
            if not self.allow_non_finite:

                def depth_check(data: np.ndarray, index: Index) -> None:
                    V.check_finite_depth(data, index, len(dataset), self._h5_path, key)

            return H5Series(dataset, self._h5_path, self._depth_transform_metres, check=depth_check)
        check = None
        if dataset.dtype.kind == "f" and not K.is_pointcloud_key(key) and not self.allow_non_finite:

            def check(data: np.ndarray, index: Index) -> None:
                V.check_finite(data, index, len(dataset), self._h5_path, key)

        return H5Series(dataset, self._h5_path, check=check)

    def _open_video(self, key: str):
        path = self._video_keys[key]
        if K.is_rgb_image_key(key):
            return RgbVideoReader(path, image_size=self.image_size)
        hit = find_depth_file(self.path, key)
        if hit is None:  # pragma: no cover - scanned above
            raise MissingKeyError("depth video vanished", path=path, key=key)
        return hit[1].reader(hit[0])

    def _video_series(self, key: str) -> VideoSeries:
        reader = self._open_video(key)
        if len(reader) != self._length:
            reader.close()
            raise RmbFormatError(
                f"video has {len(reader)} frames but the episode has {self._length} steps",
                path=self._video_keys[key],
                key=key,
            )
        if K.is_rgb_image_key(key):
            series = VideoSeries(reader)  # the reader resizes (image_size)
        else:
            series = VideoSeries(reader, self._depth_transform_mm)
        self._open_series.append(series)
        return series

    def _rgb_transform(self, images: np.ndarray) -> np.ndarray:
        return _resize(images, self.image_size, cv2.INTER_LINEAR)

    def _depth_transform_mm(self, depth_mm: np.ndarray) -> np.ndarray:
        return self._depth_transform_metres(mm_to_metres(depth_mm))

    def _depth_transform_metres(self, depth: np.ndarray) -> np.ndarray:
        depth = np.asarray(depth, dtype=np.float32)
        if self.image_size is None:
            return depth
        # Nearest neighbour: linear interpolation would invent depths between foreground and
        # background (flying pixels) and smear "no data" zeros.
        return _resize(depth, self.image_size, self._depth_interpolation)

    @property
    def video_digests(self) -> dict[str, str]:
        """Video file name -> SHA-256 recorded when the episode was written (empty if none).

        Raises:
            RmbFormatError: The ``video_sha256`` attribute is malformed.
        """
        if ATTR_VIDEO_SHA256 not in self.attrs:
            return {}
        return parse_digests(self.attrs[ATTR_VIDEO_SHA256], self._h5_path)

    def verify_digests(self) -> int:
        """Hash every video file whose digest the writer recorded and compare.

        Episodes written by the original RMB (or single-file ones) record none: nothing is
        checked for them. HDF5 data needs no such step: its checksums are verified on read.

        Returns:
            The number of files checked.

        Raises:
            RmbFormatError: A file differs from what was written or is missing (named).
        """
        digests = self.video_digests
        check_digests(self.path, digests)
        return len(digests)

    def validate(self, *, frames: bool = False) -> None:
        """Check all that is cheap to check; raise :class:`RmbFormatError` at the first fault.

        Beyond what opening checked: every key holds ``len(self)`` steps (videos: frame count,
        packet index, pixel format), low-dimensional values are finite (unless
        ``allow_non_finite``), ``time`` is regular (:attr:`fps`), ``world_idx`` is an integer
        and every depth camera's ``fovy`` attribute a field of view. ``frames=True`` also
        decodes every video frame (slow: the only way to find corrupt frames).
        """
        for key in self.keys():
            series = self._series(key)
            if isinstance(series, VideoSeries):
                try:
                    if frames:
                        for start in range(0, len(series), 32):
                            series[start : start + 32]
                finally:
                    series.close()
                    self._open_series.remove(series)
            elif not K.is_image_key(key):
                series[:]
        if K.TIME in self:
            self.fps  # noqa: B018 - checks regularity
        world = self.attrs.get(K.ATTR_WORLD_IDX)
        if world is not None and not isinstance(world, int | np.integer):
            raise RmbFormatError(
                f"attribute holds {world!r}; expected an integer world index",
                path=self._h5_path,
                key=K.ATTR_WORLD_IDX,
            )
        for key in self.keys():
            if K.is_depth_image_key(key) and K.fovy_attr(K.camera_of(key)) in self.attrs:
                self.fovy(K.camera_of(key))

    # ------------------------------------------------------------------ lifetime
    def close(self) -> None:
        for series in self._open_series:
            series.close()
        self._open_series.clear()
        if self._h5.id.valid:
            self._h5.close()

    def __enter__(self) -> Episode:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"Episode({str(self.path)!r}, format={self.format.value!r}, steps={len(self)})"


def open_episode(
    path: str | Path,
    *,
    image_size: tuple[int, int] | None = None,
    cache: bool = False,
    allow_non_finite: bool = False,
    allow_missing_depth: bool = False,
    verify: bool = False,
) -> Episode:
    """Open an RMB episode (``.rmb`` directory or ``.hdf5`` file) for reading.

    ``image_size=(width, height)`` resizes images on read (like RMB's loader); ``cache=True``
    keeps every key read in RAM; ``allow_non_finite=True`` returns NaN/inf in low-dimensional
    and depth images instead of raising (see :class:`Episode`). A camera of ``camera_names``
    without depth images while other listed cameras have them is refused (naming the missing
    file) unless ``allow_missing_depth=True``. ``verify=True`` hashes every video file whose
    SHA-256 the writer recorded and compares (:meth:`Episode.verify_digests`). Raises
    :class:`RmbFormatError` for data that breaks the RMB format (see the module documentation).
    """
    return Episode(
        path,
        image_size=image_size,
        cache=cache,
        allow_non_finite=allow_non_finite,
        allow_missing_depth=allow_missing_depth,
        verify=verify,
    )


def find_episodes(*sources: str | Path) -> list[Path]:
    """Expand files and directories into episode paths, like RMB's dataset scan.

    A directory contributes its ``*.rmb`` and ``*.hdf5`` entries (sorted, not recursive), but
    never ``*.rmb.hdf5`` (the inner file of a compact episode).
    """
    found: list[Path] = []
    for source in sources:
        source = Path(source)
        if source.suffix in (K.COMPACT_SUFFIX, K.SINGLE_HDF5_SUFFIX):
            found.append(source)
        elif source.is_dir():
            for entry in sorted(source.iterdir()):
                name = entry.name
                if name.startswith(".") or name.endswith(K.COMPACT_MAIN_FILE.removeprefix("main")):
                    continue
                if name.endswith((K.COMPACT_SUFFIX, K.SINGLE_HDF5_SUFFIX)):
                    found.append(entry)
        else:
            raise RmbFormatError("not an episode (.rmb/.hdf5) nor a directory", path=source)
    return found
