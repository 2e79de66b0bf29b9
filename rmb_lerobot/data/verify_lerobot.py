"""``rmb-data verify`` of a LeRobotDataset v3 on disk (what ``rmb-convert to-lerobot`` writes).

Reads ``meta/info.json``, every parquet file in full (``meta/episodes``, ``meta/tasks``, ``data``)
and decodes every frame of every video file. Checks: episode indices ``0..N-1`` each with
``length`` rows, ``frame_index`` counting from 0, ``index`` the global row number,
``timestamp = frame_index / fps``, totals in ``info.json``, NaN/inf in float columns, every
number of ``meta/stats.json`` and of the per-episode statistics finite, and per video feature
and episode as many decodable frames in ``[from_timestamp, to_timestamp)`` as it has rows.
"""

from __future__ import annotations

import json
import math
from collections import defaultdict
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from rmb_lerobot.codecs.video import VideoFrameReader
from rmb_lerobot.data.verify_report import Report
from rmb_lerobot.data.verify_rmb import CHUNK, Progress
from rmb_lerobot.errors import RmbFormatError

INFO = Path("meta/info.json")
STATS = Path("meta/stats.json")
_TIME_TOLERANCE_S = 1e-4  # LeRobot's default tolerance_s


def is_lerobot_dataset(path: Path) -> bool:
    """Whether ``path`` is the root of a LeRobot dataset (it has ``meta/info.json``)."""
    return (path / INFO).is_file()


def _say(message: str, path: Path, key: str | None = None) -> str:
    return str(RmbFormatError(message, path=path, key=key))


def verify_dataset(
    root: Path, report: Report, progress: Progress, *, allow_non_finite: bool = False
) -> None:
    """Check one LeRobot v3 dataset; every problem becomes a finding of ``report``.

    Args:
        root: The dataset's root directory.
        report: Where findings and counts go.
        progress: Called with the video frames decoded, as they are.
        allow_non_finite: Do not report NaN/inf in the data (statistics are always checked).
    """
    info: dict[str, Any] | None = None
    with report.check("info", root / INFO):
        info = json.loads((root / INFO).read_text())
        version = str(info.get("codebase_version", ""))
        if not version.startswith("v3"):
            report.add("info", _say(f"codebase_version {version!r}; expected v3.x", root / INFO))
            return
        fps = float(info["fps"])
    if info is None:
        return
    episodes = _read_tables(root, "meta/episodes/*/*.parquet", report)
    _read_tables(root, "meta/tasks.parquet", report)
    data = _read_tables(root, "data/*/*.parquet", report)
    if episodes is None or data is None:
        return
    with report.check("index", root):
        _check_rows(root, info, episodes, data, fps, report)
    if not allow_non_finite:
        _check_finite_columns(root, data, report)
    _check_stats(root, episodes, report)
    videos = [k for k, f in info.get("features", {}).items() if f.get("dtype") == "video"]
    for key in videos:
        with report.check("video", root):
            _check_video_feature(root, info, episodes, key, fps, report, progress)


def _read_tables(root: Path, pattern: str, report: Report) -> pa.Table | None:
    """Every parquet file matching ``pattern`` read in full and concatenated (None: broken)."""
    files = sorted(root.glob(pattern))
    if not files:
        report.add("parquet", _say(f"no files {pattern}", root))
        return None
    tables = []
    for file in files:
        with report.check("parquet", file):
            tables.append(pq.ParquetFile(file).read())
            report.counts["datasets"] += 1
    if len(tables) != len(files):
        return None
    try:
        return pa.concat_tables(tables, promote_options="default")
    except (pa.ArrowInvalid, pa.ArrowTypeError) as exc:
        report.add("parquet", _say(f"files disagree on their columns: {exc}", root / pattern))
        return None


def _column(table: pa.Table, name: str, where: Path) -> np.ndarray:
    if name not in table.column_names:
        raise RmbFormatError("column missing", path=where, key=name)
    return _numpy(table[name])


def _numpy(column: pa.ChunkedArray) -> np.ndarray:
    """A column as numpy (without ``ChunkedArray.to_numpy``, which imports pandas: seconds)."""
    return column.combine_chunks().to_numpy(zero_copy_only=False)


def _check_rows(
    root: Path, info: dict, episodes: pa.Table, data: pa.Table, fps: float, report: Report
) -> None:
    data_dir, meta_dir = root / "data", root / "meta/episodes"
    index = _column(episodes, "episode_index", meta_dir).astype(np.int64)
    lengths = _column(episodes, "length", meta_dir).astype(np.int64)
    if not np.array_equal(np.sort(index), np.arange(len(index))):
        report.add(
            "index",
            _say(
                f"episode indices {index.tolist()[:20]}; expected 0..N-1", meta_dir, "episode_index"
            ),
        )
    for name, actual in (("total_episodes", len(index)), ("total_frames", data.num_rows)):
        if int(info.get(name, -1)) != actual:
            report.add("info", _say(f"says {info.get(name)}; found {actual}", root / INFO, name))
    rows = _column(data, "episode_index", data_dir).astype(np.int64)
    if not np.array_equal(_column(data, "index", data_dir), np.arange(data.num_rows)):
        report.add("index", _say("rows are not numbered 0..N-1", data_dir, "index"))
    frame_index = _column(data, "frame_index", data_dir).astype(np.int64)
    timestamp = _column(data, "timestamp", data_dir).astype(np.float64)
    for episode, length in zip(index.tolist(), lengths.tolist(), strict=True):
        at = np.flatnonzero(rows == episode)
        where = f"episode {episode}"
        if len(at) != length:
            report.add(
                "index",
                _say(f"{where} has {len(at)} rows; meta says {length}", data_dir, "episode_index"),
            )
            continue
        if not np.array_equal(frame_index[at], np.arange(length)):
            report.add(
                "index",
                _say(f"{where}: frame_index is not 0..{length - 1}", data_dir, "frame_index"),
            )
        expected = np.arange(length) / fps
        off = np.abs(timestamp[at] - expected)
        if not (off <= _TIME_TOLERANCE_S).all():
            bad = int(np.argmax(off > _TIME_TOLERANCE_S))
            report.add(
                "time",
                _say(
                    f"{where}: frame {bad} at {timestamp[at][bad]!r} s; expected "
                    f"{expected[bad]:.6f} s (frame_index / fps {fps:g})",
                    data_dir,
                    "timestamp",
                ),
            )


def _check_finite_columns(root: Path, data: pa.Table, report: Report) -> None:
    for name in data.column_names:
        column = data[name]
        kind = column.type
        while pa.types.is_list(kind) or pa.types.is_fixed_size_list(kind):
            column = pa.chunked_array([c.flatten() for c in column.chunks], kind.value_type)
            kind = kind.value_type
        if not pa.types.is_floating(kind):
            continue
        values = _numpy(column)
        bad = int(np.count_nonzero(~np.isfinite(values)))
        if bad:
            report.add("values", _say(f"{bad} non-finite values (NaN/inf)", root / "data", name))


def _numbers(value: Any, path: str = "") -> Iterator[tuple[str, float]]:
    if isinstance(value, dict):
        for key, item in value.items():
            yield from _numbers(item, f"{path}/{key}" if path else str(key))
    elif isinstance(value, list | tuple | np.ndarray):
        for item in value:
            yield from _numbers(item, path)
    elif isinstance(value, int | float | np.number) and not isinstance(value, bool):
        yield path, float(value)


def _check_stats(root: Path, episodes: pa.Table, report: Report) -> None:
    with report.check("stats", root / STATS):
        stats = json.loads((root / STATS).read_text())
        bad = sorted({path for path, v in _numbers(stats) if not math.isfinite(v)})
        if bad:
            report.add("stats", _say(f"non-finite statistics: {', '.join(bad[:10])}", root / STATS))
    columns = [c for c in episodes.column_names if c.startswith("stats/")]
    per_episode = {c: episodes[c].to_pylist() for c in columns}
    bad = sorted(
        {c for c, v in per_episode.items() for _, x in _numbers(v) if not math.isfinite(x)}
    )
    if bad:
        report.add(
            "stats",
            _say(
                f"non-finite per-episode statistics: {', '.join(bad[:10])}", root / "meta/episodes"
            ),
        )


def _check_video_feature(
    root: Path,
    info: dict,
    episodes: pa.Table,
    key: str,
    fps: float,
    report: Report,
    progress: Progress,
) -> None:
    """Decode every file of one video feature; count each episode's frames in its span."""
    prefix = f"videos/{key}/"
    meta_dir = root / "meta/episodes"
    files: dict[Path, list[tuple[int, float, float, int]]] = defaultdict(list)
    chunk = _column(episodes, prefix + "chunk_index", meta_dir)
    file_index = _column(episodes, prefix + "file_index", meta_dir)
    start = _column(episodes, prefix + "from_timestamp", meta_dir)
    stop = _column(episodes, prefix + "to_timestamp", meta_dir)
    index = _column(episodes, "episode_index", meta_dir)
    lengths = _column(episodes, "length", meta_dir)
    for i in range(episodes.num_rows):
        path = root / info["video_path"].format(
            video_key=key, chunk_index=int(chunk[i]), file_index=int(file_index[i])
        )
        files[path].append((int(index[i]), float(start[i]), float(stop[i]), int(lengths[i])))
    for path, spans in files.items():
        with report.check("video", path):
            times = _decode_times(path, report, progress)
            half = 0.5 / fps
            for episode, first, last, length in spans:
                count = int(np.count_nonzero((times >= first - half) & (times < last - half)))
                if count != length:
                    report.add(
                        "video",
                        _say(
                            f"episode {episode} has {count} frames in [{first:.4f}, {last:.4f}) s; "
                            f"expected {length}",
                            path,
                            key,
                        ),
                    )


def _decode_times(path: Path, report: Report, progress: Progress) -> np.ndarray:
    """Decode every frame of a video file in order; their presentation times in seconds."""
    times: list[float] = []
    with VideoFrameReader(path) as reader:
        count = len(reader)
        for first in range(0, count, CHUNK):
            frames = reader.frames(slice(first, min(count, first + CHUNK)))
            times += [float(f.pts * reader.time_base) for f in frames]
            report.counts["frames"] += len(frames)
            progress(len(frames))
    return np.asarray(times)
