"""``--workers K``: convert K contiguous slices of the episodes in parallel, then merge them.

Each worker process writes a complete dataset (a shard) for its slice with
:func:`.write.write_dataset`; LeRobot's ``aggregate_datasets`` then merges the shards in order
by remuxing (videos are not re-encoded), so episode order and indices match a one-process run.

Nothing may outlive the conversion or escape its staging (:mod:`.atomic`): the shards are built
in the staging's ``.shards`` sibling and the workers' temporary files go to the staging's
scratch directory. Workers are *spawned*: a fork server would listen on a socket in a
``pymp-*`` directory, which a killed run leaves in ``$TMPDIR`` and which cannot move into the
staging (socket paths are limited to 107 bytes); spawning needs no such directory, at the cost
of each worker importing LeRobot itself (in parallel). Workers end with the converting process,
however it ends: on an exception, Ctrl-C or SIGTERM they are terminated, on SIGKILL each
worker's watcher thread sees the parent gone, so none keeps writing into a removed temporary.
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import itertools
import multiprocessing
import os
import queue
import select
import tempfile
import threading
import time
from collections.abc import Sequence
from pathlib import Path

from lerobot.datasets.aggregate import aggregate_datasets

from rmb_lerobot.converters.plan import ConversionPlan, EpisodeSource
from rmb_lerobot.converters.progress import Progress, QueueProgress, forward
from rmb_lerobot.converters.write import VideoSettings, write_dataset

_EVENTS = None  # the worker's end of the progress queue


def _exit_with(pid: int) -> None:
    """End this process as soon as process ``pid`` (the converting one) has ended."""

    def watch() -> None:
        try:
            fd = os.pidfd_open(pid)
        except (AttributeError, OSError):  # not Linux >= 5.3: poll
            while _alive(pid):
                time.sleep(0.5)
        else:
            select.select([fd], [], [])  # readable once the process has exited
        os._exit(1)

    threading.Thread(target=watch, name="exit-with-parent", daemon=True).start()


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _init_worker(events, parent_pid: int, scratch: str) -> None:
    global _EVENTS
    _EVENTS = events
    tempfile.tempdir = scratch  # LeRobot's temporary videos stay in the staging
    _exit_with(parent_pid)
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


def _terminate(pool: concurrent.futures.ProcessPoolExecutor) -> None:
    """Stop the workers now (shutdown would wait for their current shard)."""
    processes = list((getattr(pool, "_processes", None) or {}).values())
    for process in processes:
        with contextlib.suppress(Exception):
            process.terminate()
    for process in processes:
        with contextlib.suppress(Exception):
            process.join(timeout=10)


def write_sharded(
    root: Path,
    repo_id: str,
    plan: ConversionPlan,
    video: VideoSettings,
    workers: int,
    progress: Progress,
    work: Path,
) -> Path:
    """Like :func:`.write.write_dataset` for all episodes, with ``workers`` processes.

    ``work`` (created here, removed by the caller's staging) holds the shards.
    """
    slices = split(plan.episodes, workers)
    work.mkdir(parents=True)
    scratch = tempfile.gettempdir()  # the staging's scratch directory (see .atomic)
    context = multiprocessing.get_context("spawn")
    shard_ids = [f"{repo_id}-shard{i:03d}" for i in range(len(slices))]
    shard_roots = [work / f"shard-{i:03d}" for i in range(len(slices))]
    events = context.Queue()
    pool = concurrent.futures.ProcessPoolExecutor(
        len(slices),
        mp_context=context,
        initializer=_init_worker,
        initargs=(events, os.getpid(), scratch),
    )
    try:
        futures = [
            pool.submit(_write_shard, shard_root, shard_id, plan, episodes, video)
            for shard_root, shard_id, episodes in zip(shard_roots, shard_ids, slices, strict=True)
        ]
        pending = set(futures)
        while pending:
            _drain(events, progress, timeout=0.2)
            pending = {f for f in pending if not f.done()}
        _drain(events, progress, timeout=0)
        for future in futures:
            future.result()  # re-raise the first worker error
    except BaseException:
        _terminate(pool)
        raise
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
        events.close()
    aggregate_datasets(shard_ids, repo_id, roots=shard_roots, aggr_root=root)
    return root


def _drain(events, progress: Progress, timeout: float) -> None:
    try:
        event = events.get(timeout=timeout) if timeout else events.get_nowait()
        forward(event, progress)
        while True:
            forward(events.get_nowait(), progress)
    except queue.Empty:
        pass
