"""Record scripted-expert demonstrations as RMB episodes (what ``rmb-collect`` runs).

RMB itself needs a human with a 3D mouse; here each task's scripted expert drives the env and
:class:`rmb_lerobot.EpisodeWriter` records every key and attribute the original recorder writes.
Episodes are written atomically, so an interrupted collection leaves only complete episodes.
Workers are separate processes (spawned), each with its own env.

Interrupts (SIGINT, SIGTERM; see :mod:`rmb_lerobot.envs.interrupts`): the episode being
recorded is aborted (its temporary removed). With workers, the parent alone handles them:
workers ignore SIGINT (a terminal's Ctrl-C reaches the whole process group) and keep SIGTERM's
default action. The parent asks its workers to stop through a shared flag, which each checks
between two steps (the episode in progress is aborted, its temporary removed), and waits for
them a bounded time (:data:`STOP_TIMEOUT_S`) before it kills any left.

Why no signal handler in the workers: a Python handler runs only when the worker's main thread
executes bytecode. A SIGTERM that arrived just before a blocking lock acquire, or whose
exception was raised inside a ``__del__`` or callback (printed as "Exception ignored", lost),
left a worker that had already set SIGTERM to ignored, blocked for ever on the queue lock that
``multiprocessing.Pool.terminate`` holds; ``terminate`` then joined it without a timeout: the
hang after the last episode of issue 30. The pool is now a
:class:`concurrent.futures.ProcessPoolExecutor`, which also ends the run with
:class:`WorkerDied` when a worker is killed from outside (``Pool.imap_unordered`` waited for its
episode for ever). A worker killed before it could clean up leaves a temporary whose lock died
with it; :func:`collect` removes such stale temporaries once its pool is gone, and before it
starts (see :mod:`rmb_lerobot.staging`).
"""

from __future__ import annotations

import logging
import math
import signal
import time
from collections.abc import Callable, Iterator
from concurrent.futures import Future, ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from multiprocessing.context import SpawnContext
from multiprocessing.process import BaseProcess
from pathlib import Path
from typing import Any

from rmb_lerobot.envs.interrupts import (
    raise_if_signalled,
    recording,
)
from rmb_lerobot.envs.registry import entry_for
from rmb_lerobot.episode import EpisodeFormat, EpisodeWriter
from rmb_lerobot.episode.writer import remove_legacy_temporaries
from rmb_lerobot.staging import remove_stale

logger = logging.getLogger(__name__)

# How long the parent waits for its workers to exit once the run is over (finished, stopped or
# failed) before it kills the ones left: a worker stops between two steps, or after building its
# env if it was still doing that.
STOP_TIMEOUT_S = 60.0


class WorkerDied(RuntimeError):
    """A worker process ended without returning its episode (killed from outside, crashed)."""


class StopRequested(BaseException):
    """The parent asked the workers to stop (see :class:`Collector`'s ``stop_requested``).

    A BaseException, like :class:`Interrupted`, so that no ``except Exception`` swallows it.
    """


@dataclass(frozen=True)
class CollectConfig:
    """What to record; picklable, so workers can rebuild the env from it."""

    env: str  # any name entry_for() knows: insert, MujocoUR5eInsert, rmb_ur5e_insert, ...
    out: Path
    episodes: int
    fmt: str = "rmb"
    world_idx: tuple[int, ...] | None = None  # None: every world of the task
    cameras: tuple[str, ...] | None = None  # None: every camera of the env (entry.cameras)
    image_size: tuple[int, int] = (640, 480)
    depth: bool = True
    random_shift: float = 0.0
    success_only: bool = False
    max_attempts: int = 5  # per episode, with success_only
    seed: int = 0
    depth_codec: str = "rmb-videoio"
    overwrite: bool = False
    # Cycle through the task's variants (Pick's 18 instructions) instead of drawing one per
    # episode from the seed: any N episodes cover min(N, variants) of them (see variant_of).
    cycle_variants: bool = False
    # Record RMB's fingertip tactile grids (left_tactile_sensor, right_tactile_sensor: 5 x 8).
    tactile: bool = False
    # Fingertip tactile image size (W, H) of the PyBullet envs; None: the backend's default.
    tactile_size: tuple[int, int] | None = None

    def __post_init__(self) -> None:
        if self.world_idx is None:
            object.__setattr__(self, "world_idx", tuple(range(entry_for(self.env).num_worlds)))

    def episode_path(self, index: int, world_idx: int) -> Path:
        entry = entry_for(self.env)
        suffix = EpisodeFormat.from_name(self.fmt).short_name
        return self.out / f"{entry.rmb_env_name}_world{world_idx}_{index:03d}.{suffix}"


@dataclass
class EpisodeResult:
    index: int
    path: Path | None  # None when nothing was kept
    success: bool
    steps: int
    attempts: int
    world_idx: int = 0
    failures: list[int] = field(default_factory=list)  # seeds of discarded attempts


class Collector:
    """One env + expert that records episodes; lives in a worker process (or the caller's)."""

    def __init__(
        self,
        config: CollectConfig,
        on_partial: Callable[[], None] | None = None,
        stop_requested: Callable[[], bool] | None = None,
    ):
        self.config = config
        self.on_partial = on_partial  # called when an exception aborts an episode
        # Polled before each episode and between two steps: True raises StopRequested there.
        self.stop_requested = stop_requested
        entry = entry_for(config.env)
        self.env = entry.make(
            cameras=config.cameras,
            image_size=config.image_size,
            depth=config.depth,
            random_shift=config.random_shift,
            # MuJoCo's fingertip grids are a backend option; PyBullet's tactile images are
            # cameras (--cameras tactile_left tactile_right).
            **({"tactile": True} if config.tactile else {}),
            **({"tactile_size": config.tactile_size} if config.tactile_size else {}),
        )
        self.expert = entry.load_expert_class()(self.env)
        self.variants = self.env.task.episode_variants() if config.cycle_variants else ()

    def record(self, index: int) -> EpisodeResult:
        """Record episode ``index``: world ``world_idx[index % len]``, seeds from ``seed``.

        A SIGINT/SIGTERM handled by :mod:`~rmb_lerobot.envs.interrupts` stops it between two
        steps (the episode is aborted) or right after it is complete.
        """
        with recording():
            return self._record(index)

    def _record(self, index: int) -> EpisodeResult:
        config = self.config
        world_idx = config.world_idx[index % len(config.world_idx)]
        attempts = config.max_attempts if config.success_only else 1
        result = EpisodeResult(index, None, False, 0, 0, world_idx)
        options = {"world_idx": world_idx}
        if self.variants:
            options.update(
                self.variants[variant_of(index, len(self.variants), len(config.world_idx))]
            )
        for attempt in range(attempts):
            # Distinct seeds for every (episode, attempt) pair, reproducible for the config.
            seed = config.seed + index + attempt * config.episodes
            result.attempts = attempt + 1
            success, steps = self._record_once(config.episode_path(index, world_idx), seed, options)
            result.success, result.steps = success, steps
            if success or not config.success_only:
                result.path = config.episode_path(index, world_idx)
                return result
            result.failures.append(seed)
        return result

    def _check_stop(self) -> None:
        raise_if_signalled()
        if self.stop_requested is not None and self.stop_requested():
            raise StopRequested

    def _record_once(self, path: Path, seed: int, options: dict) -> tuple[bool, int]:
        env, config = self.env, self.config
        self._check_stop()
        obs, info = env.reset(seed=seed, options=options)
        self.expert.reset()
        attrs = {**env.rmb_attrs(), "demo_name": path.stem}
        writer = EpisodeWriter(
            path, attrs, depth_codec=config.depth_codec, overwrite=config.overwrite
        )
        try:
            for _ in range(env.task.max_episode_steps):
                self._check_stop()
                action = self.expert(obs)
                writer.append(env.rmb_step_data(action))
                obs, _, terminated, truncated, info = env.step(action)
                if terminated or truncated:
                    # Keep the final state (reward 1 on success), holding the last command.
                    writer.append(env.rmb_step_data())
                    break
            success = bool(info["is_success"])
            if config.success_only and not success:
                writer.abort()
            else:
                writer.close()
            return success, len(writer)
        except BaseException:
            writer.abort()
            if self.on_partial is not None:
                self.on_partial()
            raise

    def close(self) -> None:
        self.env.close()


class Collection(Iterator[EpisodeResult]):
    """The results of :func:`collect`, yielded as episodes finish, plus what was cleaned up.

    Iterating records the episodes; closing it (or an exception in the loop, e.g.
    :class:`Interrupted`) stops the workers and removes the episodes they were recording.
    """

    def __init__(self, config: CollectConfig, workers: int = 1):
        self.config = config
        self.workers = workers
        self.partials_removed = 0  # episodes an exception or signal stopped half-way
        self._results = self._run()

    def __next__(self) -> EpisodeResult:
        return next(self._results)

    def close(self) -> None:
        self._results.close()

    def _count_partial(self) -> None:
        self.partials_removed += 1

    def _run(self) -> Iterator[EpisodeResult]:
        config = self.config
        entry = entry_for(config.env)
        if config.cycle_variants and not entry.load_task_class()().episode_variants():
            raise ValueError(
                f"{entry.rmb_env_name} has one variant only: nothing to cycle "
                "(--cycle-instructions is for language-conditioned tasks such as pick)"
            )
        config.out.mkdir(parents=True, exist_ok=True)
        remove_stale(config.out)  # temporaries of ended runs; a live parallel run's stay
        remove_legacy_temporaries(config.out)
        if self.workers <= 1:
            collector = Collector(config, on_partial=self._count_partial)
            try:
                for index in range(config.episodes):
                    yield collector.record(index)
            finally:
                collector.close()
            return
        yield from self._run_pool()

    def _run_pool(self) -> Iterator[EpisodeResult]:
        config = self.config
        # spawn, not fork (EGL/OpenGL and threads) nor the process-wide forkserver: a spawned
        # worker starts with SIGINT ignored if it was ignored here when it was spawned (below).
        context = _TrackingSpawnContext()
        stop = context.RawValue("b", 0)  # a shared byte without a lock, which no dead worker holds
        # Workers start with SIGINT ignored, so a Ctrl-C while they import and build their env
        # cannot print their tracebacks. The executor spawns them in submit(). A Ctrl-C to this
        # process in these few milliseconds is lost; the next one is handled.
        previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
        try:
            executor = ProcessPoolExecutor(
                self.workers, mp_context=context, initializer=_init_worker, initargs=(config, stop)
            )
            futures = [executor.submit(_record_in_worker, i) for i in range(config.episodes)]
        finally:
            signal.signal(signal.SIGINT, previous)
        try:
            for future in as_completed(futures):
                try:
                    result = future.result()
                except BrokenProcessPool:
                    raise WorkerDied(_describe_dead(context.processes, config.out)) from None
                if isinstance(result, EpisodeResult):
                    yield result
        finally:
            stop.value = 1  # a no-op for a finished run: every episode is done
            _shut_down(executor, context.processes)
            self.partials_removed += sum(_aborted(future) for future in futures)
            # Workers that died before cleaning up (killed from outside, or after the timeout)
            # left temporaries whose locks died with them.
            self.partials_removed += len(remove_stale(config.out))


def variant_of(index: int, variants: int, worlds: int) -> int:
    """The variant (e.g. Pick's instruction) of episode ``index``, with ``--cycle-instructions``.

    Consecutive episodes take consecutive variants, so any ``N`` episodes cover ``min(N,
    variants)`` of them and each variant gets ``N / variants`` episodes (rounded). The worlds
    cycle alongside (episode ``index`` is in world ``world_idx[index % worlds]``); where the two
    cycles share a period (18 instructions, 6 worlds: every 18 episodes), the variants shift by
    one at each full period, so that ``variants * worlds`` episodes hold every (variant, world)
    pair once.

    Args:
        index: The episode's index in the run.
        variants: How many variants the task has (>= 1).
        worlds: How many worlds the run cycles through (>= 1).

    Returns:
        The variant's index, in ``0..variants - 1``.
    """
    period = math.lcm(variants, worlds)
    return (index + index // period) % variants


class _TrackingSpawnContext(SpawnContext):
    """The spawn context, keeping the processes it starts (exit codes, a bounded join)."""

    def __init__(self) -> None:
        self.processes: list[BaseProcess] = []

    def Process(self, *args: Any, **kwargs: Any) -> BaseProcess:  # the context's API name
        process = super().Process(*args, **kwargs)
        self.processes.append(process)
        return process


def _shut_down(executor: ProcessPoolExecutor, processes: list[BaseProcess]) -> None:
    """Stop ``executor``'s workers: let them exit, kill those alive after :data:`STOP_TIMEOUT_S`."""
    executor.shutdown(wait=False, cancel_futures=True)
    deadline = time.monotonic() + STOP_TIMEOUT_S
    for process in processes:
        process.join(max(0.0, deadline - time.monotonic()))
        if process.is_alive():
            logger.warning(
                "worker process %d still running %.0f s after the end of the run: killed",
                process.pid,
                STOP_TIMEOUT_S,
            )
            process.kill()
            process.join()
    executor.shutdown(wait=True)  # the executor's own threads, now that no worker is left


def _aborted(future: Future) -> bool:
    """Whether a worker aborted an episode in progress for this future (stop requested)."""
    if future.cancelled() or not future.done() or future.exception() is not None:
        return False
    result = future.result()
    return isinstance(result, _Stopped) and result.partial


_DEAD_WORKER_WAIT_S = 2.0


def _describe_dead(processes: list[BaseProcess], out: Path) -> str:
    """What :class:`WorkerDied` says: which workers ended, how, and what to do."""
    # A killed worker's pipes close before the kernel makes it a zombie: the pool can break a
    # moment before its exit code can be read, so wait for it briefly.
    deadline = time.monotonic() + _DEAD_WORKER_WAIT_S
    while not (dead := [p for p in processes if p.exitcode not in (None, 0)]):
        if time.monotonic() > deadline:
            break
        time.sleep(0.02)
    how = ", ".join(f"pid {p.pid} {_exit_reason(p.exitcode)}" for p in dead) or "unknown exit"
    return (
        f"a worker process ended abruptly while recording ({how}): killed from outside (kill, "
        f"the out-of-memory killer: see dmesg) or crashed; the run was stopped. Complete "
        f"episodes stay in {out}; run again (fewer --workers if memory ran out)"
    )


def _exit_reason(exitcode: int) -> str:
    if exitcode < 0:
        try:
            return f"killed by {signal.Signals(-exitcode).name}"
        except ValueError:
            return f"killed by signal {-exitcode}"
    return f"exit status {exitcode}"


def collect(config: CollectConfig, workers: int = 1) -> Collection:
    """Record ``config.episodes`` episodes, yielding each result as it finishes.

    Starts by removing stale temporaries in ``config.out`` (see :mod:`rmb_lerobot.staging`).

    Args:
        config: What to record, and where.
        workers: Worker processes (1: in this process).

    Returns:
        The results, as an iterator; iterating it raises :class:`WorkerDied` if a worker process
        ends without returning its episode.
    """
    return Collection(config, workers)


@dataclass(frozen=True)
class _Stopped:
    """A worker's answer for an episode the parent's stop request cut short or never began."""

    index: int
    partial: bool  # an episode in progress was aborted (its temporary removed)


_WORKER: Collector | None = None
_STOP: Any = None  # the parent's shared stop flag (a RawValue)
_ABORTED: list[int] = []  # episodes whose recording an exception aborted, in this call


def _init_worker(config: CollectConfig, stop: Any) -> None:
    global _WORKER, _STOP
    # The parent decides when to stop: it gets the terminal's Ctrl-C too, and sets `stop`, which
    # the collector polls between two steps. SIGTERM keeps its default action: a worker killed
    # from outside dies at once (whichever of its threads the signal reaches), and the parent
    # reports it (WorkerDied); see the module docstring for why no Python handler.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    _STOP = stop
    _WORKER = Collector(
        config, on_partial=lambda: _ABORTED.append(1), stop_requested=lambda: bool(stop.value)
    )


def _record_in_worker(index: int) -> EpisodeResult | _Stopped:
    assert _WORKER is not None, "worker not initialised"
    if _STOP.value:
        return _Stopped(index, partial=False)
    _ABORTED.clear()
    try:
        return _WORKER.record(index)
    except StopRequested:
        return _Stopped(index, partial=bool(_ABORTED))
