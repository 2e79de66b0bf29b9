"""Tile lerobot-eval's rollout videos into one video, success marked (RMB's TileRolloutVideos).

RMB's tool cuts one screen recording of consecutive rollouts apart (by detecting when the
window restarts) and tiles the pieces, framing each green (success) or red (failure) from a
success list given by hand. lerobot-eval already writes one video per rollout,
``OUTPUT/videos/<env type>_<task id>/eval_episode_<k>.mp4`` (the first 10 episodes of each
task), and records the outcomes in ``OUTPUT/eval_info.json``: ``per_task[i].metrics.successes[k]``
belongs to ``video_paths[k]``. So here the videos are found, their outcomes read from that
file, and the tiles framed the same way (green, red; white when the outcome is unknown), each
labelled with its task and episode. Videos of different lengths hold their last frame, as in
RMB's tool. The output is H.264 (yuv420p) written with PyAV, atomically.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

import av
import cv2
import numpy as np
from tqdm import tqdm

from rmb_lerobot.errors import RmbFormatError
from rmb_lerobot.staging import Staging

EVAL_INFO = "eval_info.json"
_EPISODE = re.compile(r"eval_episode_(\d+)\.mp4")
GREEN = (0, 160, 0)
RED = (220, 0, 0)
WHITE = (255, 255, 255)


@dataclass(frozen=True)
class Rollout:
    video: Path
    success: bool | None  # None: unknown
    label: str


def _sort_key(path: Path) -> tuple:
    match = _EPISODE.fullmatch(path.name)
    return (str(path.parent), int(match[1]) if match else math.inf, path.name)


def find_eval_info(video_dir: Path) -> Path | None:
    """``eval_info.json`` in ``video_dir`` or up to two levels above it (lerobot-eval's output)."""
    for directory in (video_dir, *list(video_dir.resolve().parents)[:2]):
        candidate = directory / EVAL_INFO
        if candidate.is_file():
            return candidate
    return None


def read_successes(eval_info: Path) -> dict[tuple[str, str], bool]:
    """(task directory name, video file name) -> success, from lerobot-eval's eval_info.json."""
    try:
        info = json.loads(eval_info.read_text())
    except (OSError, ValueError) as exc:
        raise RmbFormatError(f"cannot read lerobot-eval's results: {exc}", path=eval_info) from exc
    found: dict[tuple[str, str], bool] = {}

    def add(video_paths, successes) -> None:
        for k, video in enumerate(video_paths or []):
            if k < len(successes):
                found[(Path(video).parent.name, Path(video).name)] = bool(successes[k])

    if not isinstance(info, dict):
        raise RmbFormatError("expected a JSON object as lerobot-eval writes", path=eval_info)
    for task in info.get("per_task", []):  # LeRobot >= 0.4: one entry per (env type, task id)
        metrics = task.get("metrics", {})
        add(metrics.get("video_paths"), metrics.get("successes", []))
    if "per_episode" in info:  # older single-task layout
        add(info.get("video_paths"), [ep.get("success") for ep in info["per_episode"]])
    return found


def find_rollouts(
    video_dir: str | Path,
    *,
    eval_info: str | Path | None = None,
    successes: Sequence[bool] | None = None,
) -> list[Rollout]:
    """The rollout videos under ``video_dir`` in order, with their outcomes.

    ``video_dir`` is lerobot-eval's output directory, its ``videos`` directory or one task's
    directory. Outcomes come from ``successes`` (one per video, in order) if given, else from
    ``eval_info`` (default: found beside or above ``video_dir``), else are unknown.
    """
    root = Path(video_dir)
    if not root.is_dir():
        raise RmbFormatError("not a directory of rollout videos", path=root)
    videos = sorted(root.rglob("eval_episode_*.mp4"), key=_sort_key) or sorted(root.rglob("*.mp4"))
    if not videos:
        raise RmbFormatError("no videos (eval_episode_*.mp4 or *.mp4) found", path=root)
    if successes is not None and len(successes) != len(videos):
        raise ValueError(
            f"{len(successes)} successes given for {len(videos)} videos under {root} "
            f"(first: {videos[0].name}); give one per video, in order"
        )
    info_path = Path(eval_info) if eval_info is not None else find_eval_info(root)
    if eval_info is not None and not Path(eval_info).is_file():
        raise RmbFormatError("lerobot-eval results not found", path=eval_info)
    known = read_successes(info_path) if info_path is not None and successes is None else {}
    task_dirs = {video.parent for video in videos}
    rollouts = []
    for i, video in enumerate(videos):
        match = _EPISODE.fullmatch(video.name)
        label = f"ep {match[1]}" if match else video.stem
        if len(task_dirs) > 1:
            label = f"{video.parent.name} {label}"
        success = (
            successes[i] if successes is not None else known.get((video.parent.name, video.name))
        )
        rollouts.append(Rollout(video, None if success is None else bool(success), label))
    return rollouts


def _frames(path: Path, size: tuple[int, int]) -> Iterator[np.ndarray]:
    try:
        with av.open(str(path)) as container:
            for frame in container.decode(video=0):
                image = frame.to_ndarray(format="rgb24")
                if image.shape[1::-1] != size:
                    image = cv2.resize(image, size, interpolation=cv2.INTER_AREA)
                yield image
    except av.error.FFmpegError as exc:
        raise RmbFormatError(f"cannot decode video: {exc}", path=path) from exc


def _probe(path: Path) -> tuple[int, int, Fraction, int]:
    """(width, height, frame rate, frame count or 0)."""
    try:
        with av.open(str(path)) as container:
            stream = container.streams.video[0]
            rate = stream.average_rate or stream.base_rate or Fraction(30)
            return stream.width, stream.height, Fraction(rate), int(stream.frames or 0)
    except (av.error.FFmpegError, IndexError) as exc:
        raise RmbFormatError(f"cannot open video: {exc}", path=path) from exc


def _label(tile: np.ndarray, text: str, color: tuple[int, int, int]) -> None:
    scale = max(0.25, tile.shape[0] / 320)
    thickness = max(1, round(scale * 1.5))
    (w, h), base = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, scale, thickness)
    cv2.rectangle(tile, (0, 0), (w + 4, h + base + 4), color, -1)
    cv2.putText(
        tile, text, (2, h + 2), cv2.FONT_HERSHEY_SIMPLEX, scale, WHITE, thickness, cv2.LINE_AA
    )


def tile_videos(
    rollouts: Sequence[Rollout],
    out: str | Path,
    *,
    columns: int | None = None,
    border: int | None = None,
    labels: bool = True,
    crf: int = 23,
    overwrite: bool = False,
    progress: bool = True,
) -> Path:
    """Write one video with the rollouts tiled row by row; returns ``out``.

    Tiles take the first video's size (others are resized), ``columns`` defaults to a square
    grid, ``border`` (pixels of green/red/white frame) to 1/16 of the tile's shorter side (at
    least 4: H.264 stores colour at half resolution, thinner frames smear into the picture).
    """
    if not rollouts:
        raise ValueError("no rollouts to tile")
    out = Path(out)
    if out.exists() and not overwrite:
        raise FileExistsError(f"destination exists: {str(out)!r} (pass --overwrite to replace it)")
    width, height, rate, _ = _probe(rollouts[0].video)
    counts = [_probe(r.video)[3] for r in rollouts]
    columns = columns or math.ceil(math.sqrt(len(rollouts)))
    if columns < 1:
        raise ValueError(f"columns must be >= 1, got {columns}")
    border = max(4, min(width, height) // 16) if border is None else border
    rows = math.ceil(len(rollouts) / columns)
    cell_w, cell_h = width + 2 * border, height + 2 * border
    canvas_h, canvas_w = rows * cell_h, columns * cell_w
    canvas = np.full((canvas_h + canvas_h % 2, canvas_w + canvas_w % 2, 3), WHITE, np.uint8)
    for i, rollout in enumerate(rollouts):
        y, x = (i // columns) * cell_h, (i % columns) * cell_w
        color = WHITE if rollout.success is None else GREEN if rollout.success else RED
        canvas[y : y + cell_h, x : x + cell_w] = color

    readers = [_frames(r.video, (width, height)) for r in rollouts]
    last: list[np.ndarray | None] = [None] * len(rollouts)
    total = max(counts) if all(counts) else None
    with Staging(out) as staging:
        with av.open(str(staging.path), "w", format="mp4") as container:
            stream = container.add_stream("libx264", rate=rate, options={"crf": str(crf)})
            stream.width, stream.height, stream.pix_fmt = (
                canvas.shape[1],
                canvas.shape[0],
                "yuv420p",
            )
            with tqdm(total=total, desc="tile-videos", unit="frame", disable=not progress) as bar:
                while True:
                    alive = False
                    for i, reader in enumerate(readers):
                        frame = next(reader, None) if reader is not None else None
                        if frame is None:
                            readers[i] = None
                        else:
                            alive = True
                            last[i] = frame
                    if not alive:
                        break
                    for i, frame in enumerate(last):
                        if frame is None:
                            continue
                        y = (i // columns) * cell_h + border
                        x = (i % columns) * cell_w + border
                        tile = canvas[y : y + height, x : x + width]
                        tile[:] = frame
                        if labels:
                            r = rollouts[i]
                            outcome = (
                                ""
                                if r.success is None
                                else (" success" if r.success else " failure")
                            )
                            color = (
                                (64, 64, 64) if r.success is None else GREEN if r.success else RED
                            )
                            _label(tile, r.label + outcome, color)
                    video_frame = av.VideoFrame.from_ndarray(canvas, format="rgb24")
                    container.mux(stream.encode(video_frame))
                    bar.update()
            container.mux(stream.encode(None))
        staging.commit(overwrite=overwrite)
    return out
