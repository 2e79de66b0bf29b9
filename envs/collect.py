"""Record scripted-expert demonstrations as RMB episodes (what ``rmb-collect`` runs).

RMB itself needs a human with a 3D mouse; here each task's scripted expert drives the env and
:class:`rmb_lerobot.EpisodeWriter` records every key and attribute the original recorder writes.
Episodes are written atomically, so an interrupted collection leaves only complete episodes.
Workers are separate processes (forkserver), each with its own env.
"""

from __future__ import annotations

import multiprocessing
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from rmb_lerobot.envs.registry import entry_for

from rmb_lerobot.episode import EpisodeFormat, EpisodeWriter

NUM_WORLDS = 6


@dataclass(frozen=True)
class CollectConfig:
    """What to record; picklable, so workers can rebuild the env from it."""

    env: str  # any name entry_for() knows: insert, MujocoUR5eInsert, rmb_ur5e_insert, ...
    out: Path
    episodes: int
    fmt: str = "rmb"
    world_idx: tuple[int, ...] = tuple(range(NUM_WORLDS))
    cameras: tuple[str, ...] = ("front", "left", "right", "hand")
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

    def __init__(self, config: CollectConfig):
        from rmb_lerobot.envs.base import RmbEnv

        self.config = config
        entry = entry_for(config.env)
        self.env = RmbEnv(
            entry.load_task_class()(),
            cameras=config.cameras,
            image_size=config.image_size,
            depth=config.depth,
            random_shift=config.random_shift,
        )
        self.expert = entry.load_expert_class()(self.env)
        self.variants = self.env.task.episode_variants() if config.cycle_variants else ()

    def record(self, index: int) -> EpisodeResult:
        """Record episode ``index``: world ``world_idx[index % len]``, seeds from ``seed``."""
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
            raise

    def close(self) -> None:
        self.env.close()


_WORKER: Collector | None = None


def _init_worker(config: CollectConfig) -> None:
    global _WORKER
    _WORKER = Collector(config)


def _record_in_worker(index: int) -> EpisodeResult:
    assert _WORKER is not None, "worker not initialised"
    return _WORKER.record(index)


def collect(config: CollectConfig, workers: int = 1) -> Iterator[EpisodeResult]:
    """Record ``config.episodes`` episodes, yielding each result as it finishes."""
    if config.cycle_variants and not entry_for(config.env).load_task_class()().episode_variants():
        raise ValueError(
            f"{entry_for(config.env).rmb_env_name} has one variant only: nothing to cycle "
            "(--cycle-instructions is for language-conditioned tasks such as pick)"
        )
    config.out.mkdir(parents=True, exist_ok=True)
    indices: Sequence[int] = range(config.episodes)
    if workers <= 1:
        collector = Collector(config)
        try:
            for index in indices:
                yield collector.record(index)
        finally:
            collector.close()
        return
    context = multiprocessing.get_context("forkserver")
    with context.Pool(workers, initializer=_init_worker, initargs=(config,)) as pool:
        yield from pool.imap_unordered(_record_in_worker, indices)
