"""``rmb-data verify`` of one RMB episode (compact ``NAME.rmb/`` or single-file ``NAME.hdf5``).

Reads everything once: every HDF5 dataset in full (HDF5 verifies the Fletcher-32 checksums of
files this package wrote on every read; files of the original RMB have none), every video frame
by frame through the package's own decoders (:mod:`rmb_lerobot.codecs`, which turn decoder
errors into :class:`~rmb_lerobot.errors.RmbFormatError`), and each video file's bytes when the
writer recorded their SHA-256 (:mod:`rmb_lerobot.episode.digest`). Checks: steps of every key
and frames of every video against ``time``, NaN/inf in every float key, the header against
the RMB format (what :func:`~rmb_lerobot.episode.open_episode` checks), ``time`` regular,
``world_idx`` and every ``fovy``, and every listed camera with RGB and, where any camera of
``camera_names`` has depth, depth.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from rmb_lerobot import keys as K
from rmb_lerobot.codecs.depth import DEPTH_CODECS, find_depth_file
from rmb_lerobot.codecs.video import VideoFrameReader
from rmb_lerobot.data.verify_report import READ_ERRORS, Report
from rmb_lerobot.episode import validate as V
from rmb_lerobot.episode.digest import ATTR_VIDEO_SHA256, check_digests, parse_digests
from rmb_lerobot.episode.layout import (
    RGB_VIDEO_SUFFIX,
    EpisodeFormat,
    episode_format,
    rgb_video_path,
)
from rmb_lerobot.episode.reader import open_episode
from rmb_lerobot.episode.timing import control_rate
from rmb_lerobot.errors import MissingKeyError, RmbFormatError

CHUNK = 32  # image rows or video frames per read
_READ_BYTES = 64 << 20  # rows of other datasets per read: about this many bytes

Progress = Callable[[int], None]
"""Called with the number of frames (image rows, video frames) just checked."""


def _say(message: str, path: Path, key: str | None = None) -> str:
    return str(RmbFormatError(message, path=path, key=key))


def verify_episode(
    path: Path, report: Report, progress: Progress, *, allow_non_finite: bool = False
) -> None:
    """Check one episode; every problem becomes a finding of ``report``.

    Args:
        path: ``NAME.rmb`` or ``NAME.hdf5``.
        report: Where findings and counts go.
        progress: Called with the frames checked, as they are.
        allow_non_finite: Do not report NaN/inf values.
    """
    fmt = None
    with report.check("layout", path):
        fmt = episode_format(path)
    if fmt is None:
        return
    h5_path = fmt.hdf5_path(path)
    if not h5_path.is_file():
        report.add("layout", _say(f"episode not found: expected {fmt.describe()}", h5_path))
        return
    attrs, lengths, time = _verify_hdf5(h5_path, report, progress, allow_non_finite)
    videos = _video_files(path) if fmt is EpisodeFormat.COMPACT else {}
    steps = len(time) if time is not None else None
    for key, file in videos.items():
        with report.check("video", file):
            lengths[key] = _decode(file, key, report, progress)
    _check_lengths(lengths, steps, h5_path, videos, report)
    missing = _check_cameras(path, fmt, attrs, {*lengths, *videos}, report)
    _check_header(path, time, missing, report)
    if fmt is EpisodeFormat.COMPACT and ATTR_VIDEO_SHA256 in attrs:
        _check_digests(path, h5_path, attrs[ATTR_VIDEO_SHA256], report)


def _verify_hdf5(
    h5_path: Path, report: Report, progress: Progress, allow_non_finite: bool
) -> tuple[dict[str, Any], dict[str, int], np.ndarray | None]:
    """Read every dataset in full: (attributes, rows per key, ``time`` if readable)."""
    attrs: dict[str, Any] = {}
    lengths: dict[str, int] = {}
    time = None
    with report.check("hdf5", h5_path), h5py.File(h5_path, "r") as h5:
        with report.check("attrs", h5_path):
            attrs = V.read_attrs(h5, h5_path)
        for name in sorted(h5.keys()):
            with report.check("hdf5", h5_path):
                dataset = h5[name]
                if not isinstance(dataset, h5py.Dataset) or dataset.ndim == 0:
                    continue  # the format check names these
                values = _read_dataset(dataset, name, h5_path, report, progress, allow_non_finite)
                lengths[name] = dataset.shape[0]
                if name == K.TIME:
                    time = values
    return attrs, lengths, time


def _read_dataset(
    dataset: h5py.Dataset,
    name: str,
    h5_path: Path,
    report: Report,
    progress: Progress,
    allow_non_finite: bool,
) -> np.ndarray | None:
    """Read ``dataset`` chunk by chunk; returns it whole when it is one read (low-dim keys)."""
    rows = dataset.shape[0]
    row_bytes = max(1, dataset.dtype.itemsize * int(np.prod(dataset.shape[1:], dtype=np.int64)))
    step = CHUNK if K.is_image_key(name) else max(1, _READ_BYTES // row_bytes)
    check = dataset.dtype.kind == "f" and not allow_non_finite
    bad_values, first_bad, data = 0, None, None
    for start in range(0, max(rows, 1), step):
        stop = min(rows, start + step)
        try:
            data = dataset[start:stop]
        except READ_ERRORS as exc:
            report.add(
                "hdf5",
                _say(
                    f"cannot read steps {start}..{stop - 1}: {exc} (a failed checksum means the "
                    "bytes changed after writing)",
                    h5_path,
                    name,
                ),
            )
            return None
        if check:
            bad = ~np.isfinite(data.reshape(len(data), -1))
            if bad.any():
                bad_values += int(bad.sum())
                first_bad = (
                    first_bad
                    if first_bad is not None
                    else start + int(np.flatnonzero(bad.any(axis=1))[0])
                )
        if K.is_image_key(name):
            report.counts["frames"] += stop - start
            progress(stop - start)
    report.counts["datasets"] += 1
    report.counts["checksummed"] += int(bool(dataset.fletcher32))
    if bad_values:
        what = "pixels" if K.is_depth_image_key(name) else "values"
        report.add(
            "values",
            _say(
                f"{bad_values} non-finite {what} (NaN/inf), the first at step {first_bad}",
                h5_path,
                name,
            ),
        )
    return data if step >= rows else None


def _video_files(directory: Path) -> dict[str, Path]:
    """Image key -> file of every RGB and depth stream of a compact episode."""
    found: dict[str, Path] = {}
    for entry in sorted(directory.iterdir()):
        stem = entry.name.split(".", 1)[0]
        if entry.name.endswith(RGB_VIDEO_SUFFIX) and K.is_rgb_image_key(stem):
            found[stem] = entry
        elif K.is_depth_image_key(stem) and stem not in found:
            hit = find_depth_file(directory, stem)
            if hit is not None:
                found[stem] = hit[0]
    return found


def _decode(file: Path, key: str, report: Report, progress: Progress) -> int:
    """Decode every frame of one stream in order; returns the frame count."""
    if K.is_rgb_image_key(key):
        reader: Any = VideoFrameReader(file)

        def read(a: int, b: int) -> object:
            return reader.frames(slice(a, b))
    else:
        hit = find_depth_file(file.parent, key)
        assert hit is not None  # found by _video_files
        reader = hit[1].reader(hit[0])

        def read(a: int, b: int) -> object:
            return reader[a:b]

    with reader:
        count = len(reader)
        for start in range(0, count, CHUNK):
            stop = min(count, start + CHUNK)
            read(start, stop)
            report.counts["frames"] += stop - start
            progress(stop - start)
    return count


def _check_lengths(
    lengths: dict[str, int],
    steps: int | None,
    h5_path: Path,
    videos: dict[str, Path],
    report: Report,
) -> None:
    if steps is None:
        report.add("time", _say("no readable 'time' key to count steps against", h5_path, K.TIME))
        return
    for key, rows in sorted(lengths.items()):
        if rows != steps:
            where = videos.get(key, h5_path)
            what = "frames" if key in videos else "steps"
            report.add("length", _say(f"holds {rows} {what}; 'time' has {steps} steps", where, key))


def _check_cameras(
    path: Path, fmt: EpisodeFormat, attrs: dict[str, Any], present: set[str], report: Report
) -> set[str]:
    """Listed cameras without their images; returns the missing keys."""
    missing = [key for _, _, key in V.check_names_have_images(attrs, present)]
    depth = []
    if fmt is EpisodeFormat.COMPACT:
        recorded = None
        with report.check("digest", fmt.hdf5_path(path)):
            if ATTR_VIDEO_SHA256 in attrs:
                recorded = parse_digests(attrs[ATTR_VIDEO_SHA256], fmt.hdf5_path(path))
        depth = V.cameras_missing_depth(attrs, present, recorded)
    for key in dict.fromkeys([*missing, *depth]):
        if fmt is EpisodeFormat.COMPACT:
            suffix = next(iter(DEPTH_CODECS.values())).file_suffix
            where = rgb_video_path(path, key) if K.is_rgb_image_key(key) else path / (key + suffix)
        else:
            where = path
        kind = "RGB" if K.is_rgb_image_key(key) else "depth (recorded, or others have depth)"
        report.add(
            "cameras",
            _say(f"camera {K.camera_of(key)!r} is listed but has no {kind} images", where, key),
        )
    return {*missing, *depth}


def _check_header(path: Path, time: np.ndarray | None, missing: set[str], report: Report) -> None:
    """What opening checks (format of every key, attributes), ``time``, world and fovy."""
    try:
        episode = open_episode(path, allow_non_finite=True, allow_missing_depth=True)
    except MissingKeyError as exc:
        if exc.key not in missing:  # else already reported by the camera check
            report.add("format", str(exc))
        return
    except RmbFormatError as exc:
        report.add("format", str(exc))
        return
    with episode:
        h5_path = episode.format.hdf5_path(path)
        if time is not None and np.isfinite(time).all():
            with report.check("time"):
                control_rate(time, path=h5_path, key=K.TIME)
        world = episode.attrs.get(K.ATTR_WORLD_IDX)
        if world is not None and not isinstance(world, int | np.integer):
            report.add(
                "attrs",
                _say(
                    f"holds {world!r}; expected an integer world index", h5_path, K.ATTR_WORLD_IDX
                ),
            )
        for key in episode:
            if K.is_depth_image_key(key) and K.fovy_attr(K.camera_of(key)) in episode.attrs:
                with report.check("attrs"):
                    episode.fovy(K.camera_of(key))


def _check_digests(path: Path, h5_path: Path, text: object, report: Report) -> None:
    digests = {}
    with report.check("digest", h5_path):
        digests = parse_digests(text, h5_path)
    for name, digest in digests.items():
        with report.check("digest", path / name):
            check_digests(path, {name: digest})
            report.counts["digests"] += 1
