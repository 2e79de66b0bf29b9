"""``--workers K``: convert K contiguous slices of the episodes in parallel, then merge them.

Each worker process writes a complete dataset (a shard) for its slice with
:func:`.write.write_dataset`; LeRobot's ``aggregate_datasets`` then merges the shards in order
by remuxing (videos are not re-encoded), so episode order and indices match a one-process run.
"""

from __future__ import annotations

import concurrent.futures
import itertools
import multiprocessing
import queue
import shutil
from collections.abc import Sequence
from pathlib import Path

from lerobot.datasets.aggregate import aggregate_datasets
from rmb_lerobot.converters.plan import ConversionPlan, EpisodeSource
from rmb_lerobot.converters.progress import Progress, QueueProgress, forward
from rmb_lerobot.converters.write import VideoSettings, write_dataset

_EVENTS = None  # the worker's end of the progress queue


def _init_worker(events) -> None:
    global _EVENTS
    _EVENTS = events
    # The parent shows one pair of bars for all workers; silence the libraries' own output.
    import av
    import datasets

    av.logging.set_libav_level(av.logging.ERROR)
    datasets.disable_progress_bars()


def _write_shard(
    root: Path,
    repo_id: str,
    plan: ConversionPlan,
    episodes: Sequence[EpisodeSource],
    video: VideoSettings,
) -> Path:
    return write_dataset(root, repo_id, plan, episodes, video, QueueProgress(_EVENTS))


def split(items: Sequence, parts: int) -> list[Sequence]:
    """``items`` in ``parts`` contiguous, nearly equal, non-empty slices."""
    parts = max(1, min(parts, len(items)))
    bounds = [round(i * len(items) / parts) for i in range(parts + 1)]
    return [items[a:b] for a, b in itertools.pairwise(bounds)]


def write_sharded(
    root: Path,
    repo_id: str,
    plan: ConversionPlan,
    video: VideoSettings,
    workers: int,
    progress: Progress,
) -> Path:
    """Like :func:`.write.write_dataset` for all episodes, with ``workers`` processes."""
    slices = split(plan.episodes, workers)
    work = root.with_name(root.name + ".shards")
    work.mkdir(parents=True)
    try:
        # Forkserver (as LeRobot uses for envs): the server imports LeRobot once and forks
        # workers from it, instead of every worker importing torch and LeRobot again.
        context = multiprocessing.get_context("forkserver")
        context.set_forkserver_preload([__name__])
        events = context.Queue()
        shard_ids = [f"{repo_id}-shard{i:03d}" for i in range(len(slices))]
        shard_roots = [work / f"shard-{i:03d}" for i in range(len(slices))]
        with concurrent.futures.ProcessPoolExecutor(
            len(slices), mp_context=context, initializer=_init_worker, initargs=(events,)
        ) as pool:
            futures = [
                pool.submit(_write_shard, shard_root, shard_id, plan, episodes, video)
                for shard_root, shard_id, episodes in zip(
                    shard_roots, shard_ids, slices, strict=True
                )
            ]
            pending = set(futures)
            while pending:
                _drain(events, progress, timeout=0.2)
                pending = {f for f in pending if not f.done()}
            _drain(events, progress, timeout=0)
            for future in futures:
                future.result()  # re-raise the first worker error
        aggregate_datasets(shard_ids, repo_id, roots=shard_roots, aggr_root=root)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return root


def _drain(events, progress: Progress, timeout: float) -> None:
    try:
        event = events.get(timeout=timeout) if timeout else events.get_nowait()
        forward(event, progress)
        while True:
            forward(events.get_nowait(), progress)
    except queue.Empty:
        pass
