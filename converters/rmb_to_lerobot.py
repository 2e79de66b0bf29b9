"""RMB episodes -> one LeRobotDataset v3 (what ``rmb-convert to-lerobot`` runs).

Everything is checked before anything is written (:mod:`.plan`), the dataset is built in a
hidden sibling of the destination and moved into place only when complete (:mod:`.atomic`), and
written with LeRobot's own writer (:mod:`.write`, :mod:`.shards`), plus ``meta/rmb.json``
(:mod:`.metadata`) and GR00T's ``meta/modality.json`` (:mod:`.gr00t`). What an interrupted run
left beside the destination is removed first.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from pathlib import Path

from lerobot.utils.constants import HF_LEROBOT_HOME

from rmb_lerobot.converters.atomic import prepare_destination, staged_output
from rmb_lerobot.converters.copy import COPY, check_copyable
from rmb_lerobot.converters.gr00t import write_modality
from rmb_lerobot.converters.metadata import write_rmb_metadata
from rmb_lerobot.converters.plan import ConvertOptions, plan_conversion
from rmb_lerobot.converters.progress import Bars
from rmb_lerobot.converters.shards import write_sharded
from rmb_lerobot.converters.stats import refresh_finite_stats
from rmb_lerobot.converters.write import VideoSettings, finish_metadata, write_dataset
from rmb_lerobot.envs.robots import ROBOTS
from rmb_lerobot.episode import find_episodes

logger = logging.getLogger(__name__)

LOCAL_NAMESPACE = "local"  # repo_id namespace of datasets written with --output only


def resolve_destination(repo_id: str | None, output: str | Path | None) -> tuple[str, Path]:
    """``(repo_id, root)``: ``--output`` wins; a repo id alone goes where LeRobot looks for it."""
    if repo_id is None and output is None:
        raise ValueError("give a --repo-id or an --output directory (or both)")
    if output is not None:
        root = Path(output).expanduser().absolute()
        return repo_id or f"{LOCAL_NAMESPACE}/{root.name}", root
    return repo_id, HF_LEROBOT_HOME / repo_id


def to_lerobot(
    sources: Sequence[str | Path],
    *,
    repo_id: str | None = None,
    output: str | Path | None = None,
    options: ConvertOptions | None = None,
    video_codec: str | None = None,
    workers: int = 1,
    overwrite: bool = False,
    progress: bool = True,
) -> tuple[str, Path]:
    """Convert the episodes in ``sources`` (files or directories); returns ``(repo_id, root)``.

    ``video_codec`` is LeRobot's RGB ``vcodec`` (default: LeRobot's, AV1), or ``"copy"`` to
    keep the episodes' H.264 packets (:mod:`.copy`); depth always uses LeRobot's depth encoder.
    ``options.image_features`` stores RGB as LeRobot ``image`` features (lossless PNG in the
    parquet rows) instead of video; ``video_codec`` then only matters for depth (not ``copy``).
    ``options.allow_non_finite`` keeps NaN/inf of low-dimensional keys (statistics then
    describe the finite values, :mod:`.stats`); by default such an episode is refused.
    """
    options = options or ConvertOptions()
    repo_id, root = resolve_destination(repo_id, output)
    prepare_destination(root, overwrite)
    if video_codec == COPY and options.image_features:
        raise ValueError(
            "--video-codec copy keeps the episodes' RGB videos, --image-features stores RGB as "
            "images: choose one"
        )
    VideoSettings(video_codec).rgb_encoder()  # LeRobot's check of the codec name, before any work
    plan = plan_conversion(find_episodes(*sources), options)
    video = VideoSettings(video_codec, check_copyable(plan) if video_codec == COPY else None)
    logger.info(
        "converting %d episodes (%d frames) of %s at %g Hz into %s",
        len(plan.episodes),
        plan.total_frames,
        plan.env,
        float(plan.rate),
        root,
    )
    with (
        staged_output(root, overwrite) as staging,
        Bars(len(plan.episodes), plan.total_frames, enabled=progress) as bars,
    ):
        tmp = staging.path
        if workers > 1 and len(plan.episodes) > 1:
            write_sharded(tmp, repo_id, plan, video, workers, bars, staging.sibling(".shards"))
        else:
            write_dataset(tmp, repo_id, plan, plan.episodes, video, bars)
        finish_metadata(tmp, plan)
        if plan.allow_non_finite:
            refresh_finite_stats(tmp)
        write_rmb_metadata(tmp, plan)
        robot = ROBOTS.get(plan.robot_type)
        write_modality(tmp, plan.schema, [arm.name for arm in robot.arms] if robot else None)
    return repo_id, root
