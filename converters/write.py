"""Stream RMB episodes into a LeRobotDataset through LeRobot's own writer.

Per episode: the low-dimensional keys are read at once (small) and cast to float32 with checks
(:mod:`.cast`), images are decoded in chunks straight from the episode's videos (sequential
decoding, no seeking) and handed to ``add_frame``; LeRobot's streaming encoder threads encode
them while the next chunk decodes.

Depth is clamped to the range LeRobot's depth encoder stores (0.01..10 m by default; NaN and
"no data" zeros become the near end, +inf the far end) before it reaches the encoder, whose
statistics would otherwise describe values the videos cannot hold. After the last episode,
:func:`finish_metadata` corrects what LeRobot's writer gets wrong for non-integer rates.
"""

from __future__ import annotations

import contextlib
import logging
import shutil
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import av
import numpy as np
from lerobot.configs import DepthEncoderConfig, RGBEncoderConfig, depth_encoder_defaults
from lerobot.datasets.io_utils import load_info, write_info

from rmb_lerobot import keys as K
from rmb_lerobot import lerobot_names as N
from rmb_lerobot.converters.copy import COPY, COPYABLE_CODEC
from rmb_lerobot.converters.encoder import ConversionDataset
from rmb_lerobot.converters.plan import ConversionPlan, EpisodeSource, open_source
from rmb_lerobot.converters.progress import Progress
from rmb_lerobot.converters.rate import lerobot_fps
from rmb_lerobot.episode.layout import rgb_video_path
from rmb_lerobot.errors import RmbFormatError

logger = logging.getLogger(__name__)

# Dataset frames decoded per read: bounds memory (32 x 640x480x3 = 29 MB per camera).
CHUNK = 32
_TASK = "task"  # the per-frame task string LeRobot's add_frame requires
_X265_PARAMS = "x265-params"


# x265 preset of the depth videos. They are lossless, so every preset stores the same 12-bit
# codes and LeRobot decodes them the same way; presets differ only in encoding CPU and bytes
# (benchmarks/depth_presets.py: "ultrafast" needs 0.3-0.4x the CPU of x265's default "medium"
# for 1.1-1.3x the bytes). None: x265's default, as LeRobot's recorder writes.
DEPTH_PRESET = "ultrafast"


def quiet_depth_encoder(preset: str | None = DEPTH_PRESET) -> DepthEncoderConfig:
    """LeRobot's default depth encoder at x265 ``preset``, minus x265's per-video console report.

    Args:
        preset: x265 preset name, or None for x265's default (``medium``).

    Returns:
        The encoder settings; LeRobot records them in the dataset's ``info.json``.
    """
    config = depth_encoder_defaults()
    config.preset = preset
    params = config.extra_options.get(_X265_PARAMS)
    if params is not None and config.vcodec == "hevc":
        config.extra_options = {**config.extra_options, _X265_PARAMS: f"{params}:log-level=error"}
    return config


def depth_range() -> tuple[float, float]:
    """Metres LeRobot's depth videos can hold: the encoder's quantisation range."""
    config = quiet_depth_encoder()
    return float(config.depth_min), float(config.depth_max)


def clamp_depth(depth: np.ndarray) -> tuple[np.ndarray, int]:
    """Depth metres as the dataset stores them (see the module docstring), and how many
    values were NaN/inf or beyond the far end (zeros and negatives are "no data" as usual)."""
    low, high = depth_range()
    depth = np.array(depth, dtype=np.float32)
    repaired = int(np.count_nonzero(~np.isfinite(depth) | (depth > high)))
    depth = np.nan_to_num(depth, copy=False, nan=0.0, posinf=high, neginf=0.0)
    return np.clip(depth, low, high, out=depth), repaired


def _report_depth(source: EpisodeSource, repaired: dict[str, int]) -> None:
    low, high = depth_range()
    for feature, count in repaired.items():
        if count:
            logger.warning(
                "%s: %d depth values of %r are NaN/inf or beyond %g m (LeRobot's depth range): "
                "stored as %g m (far) or, for NaN, %g m (no data)",
                source.path,
                count,
                feature,
                high,
                high,
                low,
            )


@dataclass(frozen=True)
class VideoSettings:
    """How RGB is written: LeRobot's ``vcodec`` (None: LeRobot's default) or ``"copy"``."""

    codec: str | None = None
    copied_gop: int | None = None  # keyframe interval of copied streams (from .copy)

    @property
    def copy(self) -> bool:
        return self.codec == COPY

    def rgb_encoder(self) -> RGBEncoderConfig | None:
        """LeRobot's RGB encoder settings; for copied H.264, a description of the stream."""
        if self.copy:
            return RGBEncoderConfig(vcodec=COPYABLE_CODEC, g=self.copied_gop, crf=None, preset=None)
        return RGBEncoderConfig(vcodec=self.codec) if self.codec else None


def create_dataset(
    root: Path, repo_id: str, plan: ConversionPlan, video: VideoSettings
) -> ConversionDataset:
    """An empty dataset at ``root`` (which must not exist), ready for :func:`add_episode`."""
    return ConversionDataset.create(
        repo_id=repo_id,
        fps=lerobot_fps(plan.rate),
        features=plan.schema.features(),
        root=root,
        robot_type=plan.robot_type,
        use_videos=True,
        rgb_encoder=video.rgb_encoder(),
        depth_encoder=quiet_depth_encoder(),
        streaming_encoding=True,
        # Named, so that LeRobot does not probe torchcodec (a broken install prints its loading
        # traceback; an absent one a warning): only writing happens here.
        video_backend="pyav",
    )


def add_episode(
    dataset: ConversionDataset,
    source: EpisodeSource,
    plan: ConversionPlan,
    progress: Progress,
    copy_rgb: bool = False,
) -> None:
    """Append one episode; any failure is re-raised naming the episode."""
    schema, skip = plan.schema, plan.skip
    if copy_rgb:
        dataset.video_encoder.copy_from(
            {
                N.image_key(camera): rgb_video_path(source.path, K.rgb_image_key(camera))
                for camera in schema.cameras
            }
        )
    repaired = {N.depth_image_key(c): 0 for c in schema.depth_cameras}
    try:
        with open_source(source.path, plan.allow_non_finite, plan.allow_missing_depth) as episode:
            lowdim = {key: np.asarray(episode[key][:]) for key in schema.lowdim_keys}
            arrays = schema.episode_arrays(
                lowdim, skip, path=source.path, allow_non_finite=plan.allow_non_finite
            )
            videos = {feature: episode[key] for feature, key in schema.image_keys().items()}
            steps = len(episode)
            for start in range(0, steps, CHUNK * skip):
                stop = min(steps, start + CHUNK * skip)
                images = {f: series[start:stop:skip] for f, series in videos.items()}
                for feature in repaired:
                    images[feature], count = clamp_depth(images[feature])
                    repaired[feature] += count
                first = start // skip
                for j in range(-(-(stop - start) // skip)):
                    frame = {feature: values[first + j] for feature, values in arrays.items()}
                    for feature, frames in images.items():
                        image = frames[j]
                        frame[feature] = image[..., None] if image.ndim == 2 else image
                    frame[_TASK] = source.task
                    dataset.add_frame(frame)
                progress.frames(-(-(stop - start) // skip))
            dataset.save_episode()
        _report_depth(source, repaired)
    except RmbFormatError:
        raise
    except (av.FFmpegError, ValueError, KeyError, IndexError) as exc:  # unreadable or bad data
        raise RmbFormatError(f"cannot convert episode: {exc}", path=source.path) from exc
    except BaseException as exc:
        exc.add_note(f"while converting episode {str(source.path)!r}")
        raise
    progress.episode_done()


def write_dataset(
    root: Path,
    repo_id: str,
    plan: ConversionPlan,
    episodes: Sequence[EpisodeSource],
    video: VideoSettings,
    progress: Progress,
) -> Path:
    """Convert ``episodes`` into a finalized dataset at ``root``; nothing is left on failure."""
    dataset = create_dataset(root, repo_id, plan, video)
    try:
        for source in episodes:
            add_episode(dataset, source, plan, progress, copy_rgb=video.copy)
    except BaseException:
        # Finalize first: LeRobot's writer would otherwise flush into the removed tree on exit.
        with contextlib.suppress(Exception):
            dataset.finalize()
        shutil.rmtree(root, ignore_errors=True)
        raise
    dataset.finalize()
    return root


def finish_metadata(root: Path, plan: ConversionPlan) -> None:
    """Fix ``info.json`` of a finished dataset: each video's true frame rate.

    LeRobot records ``video.fps`` as ``int(stream.base_rate)``: 31 for RMB's 125/4 streams,
    while the dataset's ``fps`` and the streams themselves run at 31.25.
    """
    info = load_info(root)
    fps = lerobot_fps(plan.rate)
    for feature in info.features.values():
        if feature.get("dtype") == "video" and feature.get("info"):
            feature["info"]["video.fps"] = fps
    write_info(info, root)
