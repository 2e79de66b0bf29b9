"""Record scripted-expert demonstrations as RMB episodes (what ``rmb-collect`` runs).

RMB itself needs a human with a 3D mouse; here each task's scripted expert drives the env and
:class:`rmb_lerobot.EpisodeWriter` records every key and attribute the original recorder writes.
Episodes are written atomically, so an interrupted collection leaves only complete episodes.
Workers are separate processes (spawned), each with its own env.

Interrupts (SIGINT, SIGTERM; see :mod:`rmb_lerobot.envs.interrupts`): the episode being
recorded is aborted (its temporary removed) and, with workers, the pool is terminated: each
worker aborts its episode on the pool's SIGTERM and exits. Workers ignore SIGINT, so a
terminal's Ctrl-C (sent to the whole process group) is handled by the parent alone. A worker
killed before it could clean up leaves a temporary whose lock died with it; :func:`collect`
removes such stale temporaries once its pool is gone, and before it starts (see
:mod:`rmb_lerobot.staging`).
"""

from __future__ import annotations

import logging
import multiprocessing
import signal
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from multiprocessing.sharedctypes import Synchronized
from pathlib import Path

from rmb_lerobot.envs.interrupts import (
    Interrupted,
    exit_on_signal,
    raise_if_signalled,
    recording,
)
from rmb_lerobot.envs.registry import entry_for
from rmb_lerobot.episode import EpisodeFormat, EpisodeWriter
from rmb_lerobot.episode.writer import remove_legacy_temporaries
from rmb_lerobot.staging import remove_stale

logger = logging.getLogger(__name__)


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
    # episode from the seed: episodes i..i+len(world_idx)-1 share a variant, across the worlds.
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

    def __init__(self, config: CollectConfig, on_partial: Callable[[], None] | None = None):
        self.config = config
        self.on_partial = on_partial  # called when an exception aborts an episode
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
            variant = (index // len(config.world_idx)) % len(self.variants)
            options.update(self.variants[variant])
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

    def _record_once(self, path: Path, seed: int, options: dict) -> tuple[bool, int]:
        env, config = self.env, self.config
        obs, info = env.reset(seed=seed, options=options)
        self.expert.reset()
        attrs = {**env.rmb_attrs(), "demo_name": path.stem}
        writer = EpisodeWriter(
            path, attrs, depth_codec=config.depth_codec, overwrite=config.overwrite
        )
        try:
            for _ in range(env.task.max_episode_steps):
                raise_if_signalled()
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
        # spawn, not fork (EGL/OpenGL and threads) nor the process-wide forkserver: a spawned
        # worker starts with SIGINT ignored if it was ignored here when it was spawned (below).
        context = multiprocessing.get_context("spawn")
        partials = context.Value("i", 0)
        # Workers start with SIGINT ignored, so a Ctrl-C while they import and build their env
        # (before _init_worker) cannot print their tracebacks. A Ctrl-C to this process in these
        # few milliseconds is lost; the next one is handled.
        previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
        try:
            pool = context.Pool(
                self.workers, initializer=_init_worker, initargs=(self.config, partials)
            )
        finally:
            signal.signal(signal.SIGINT, previous)
        try:
            yield from pool.imap_unordered(_record_in_worker, range(self.config.episodes))
        finally:
            pool.terminate()  # SIGTERM: each busy worker aborts its episode; joined here
            self.partials_removed += partials.value
            # Workers that died before cleaning up (a second SIGTERM, SIGKILL) left temporaries
            # whose locks died with them.
            self.partials_removed += len(remove_stale(self.config.out))


def collect(config: CollectConfig, workers: int = 1) -> Collection:
    """Record ``config.episodes`` episodes, yielding each result as it finishes.

    Starts by removing stale temporaries in ``config.out`` (see :mod:`rmb_lerobot.staging`).
    """
    return Collection(config, workers)


_WORKER: Collector | None = None


def _init_worker(config: CollectConfig, partials: Synchronized) -> None:
    global _WORKER
    # The parent decides when to stop: it gets the terminal's Ctrl-C too, and terminates the
    # pool, whose SIGTERM makes this worker abort its episode and exit (quietly: SystemExit).
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, exit_on_signal)

    def count_partial() -> None:
        with partials.get_lock():
            partials.value += 1

    _WORKER = Collector(config, on_partial=count_partial)


def _record_in_worker(index: int) -> EpisodeResult:
    assert _WORKER is not None, "worker not initialised"
    try:
        return _WORKER.record(index)
    except Interrupted as exc:
        raise SystemExit(exc.exit_code) from None
