"""The cells of a benchmark config, in dependency order, and where each writes.

Per task one ``collect`` cell records the most demos any policy needs, with every camera (and
depth) the task's policies use; per (task, cameras, depth, demo count) one ``convert`` cell makes
a LeRobotDataset from the first N demos (which cycle through the worlds, so every prefix is
balanced); per (policy, task, seed, demo count) one ``train`` cell; per world one ``eval`` cell,
and with ``eval_shift`` a second one on placements shifted by up to that many metres.
Layout under ``OUT`` (absolute; on a cluster a path every node sees)::

    data/<task>/rmb/                              rmb-collect
    data/<task>/<cameras>[_depth]_n<N>/           rmb-convert to-lerobot
    train/<task>/<policy>/seed<S>-n<N>/           lerobot-train --output_dir
    eval/<task>/<policy>/seed<S>-n<N>/world<K>/   lerobot-eval --output_dir (eval_info.json)
    eval/<task>/<policy>/seed<S>-n<N>/world<K>-shift<M>/   the same with --env.random_shift=M
    cells/<cell id>.json   logs/<cell id>.log     completion records, command logs
    results.jsonl  curves.jsonl  config.json  report/
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from rmb_lerobot.benchmark.cells import Cell
from rmb_lerobot.benchmark.config import BenchmarkConfig, PolicySpec
from rmb_lerobot.benchmark.recipes import (
    EnvInputs,
    TrainSpec,
    checkpoint_of,
    collect_stage,
    convert_stage,
    eval_stage,
    train_stage,
)
from rmb_lerobot.envs.collect import CollectConfig


@dataclass(frozen=True)
class DatasetKey:
    task: str
    cameras: tuple[str, ...]
    depth: bool
    demos: int

    @property
    def name(self) -> str:
        return f"{'_'.join(self.cameras)}{'_depth' if self.depth else ''}_n{self.demos}"


def eval_seed(config: BenchmarkConfig, seed: int, world: int) -> int:
    """``lerobot-eval --seed``: object shifts unseen in training, different for every seed."""
    return config.eval_seed + 100 * seed + world


def plan(config: BenchmarkConfig) -> dict[str, Cell]:
    """Every cell of ``config`` by id, upstream cells before the cells that need them."""
    out = config.out.absolute()
    cells: dict[str, Cell] = {}
    collect_cells = {task: _collect_cell(config, out, task) for task in config.tasks}
    for cell in collect_cells.values():
        if cell is not None:
            cells[cell.id] = cell
    converts: dict[DatasetKey, Cell] = {}
    trains: list[tuple[Cell, PolicySpec, str, int, int]] = []
    for policy in config.policies:
        for task in config.tasks_of(policy):
            for demos in config.demo_counts(policy, task):
                key = DatasetKey(task, config.cameras_of(policy), policy.depth, demos)
                if key not in converts:
                    converts[key] = _convert_cell(config, out, key, collect_cells[task])
                for seed in config.seeds:
                    trains.append(
                        (
                            _train_cell(config, out, policy, converts[key], key, seed),
                            policy,
                            task,
                            seed,
                            demos,
                        )
                    )
    for cell in converts.values():
        cells[cell.id] = cell
    for train, *_ in trains:
        cells[train.id] = train
    for train, policy, task, seed, demos in trains:
        for world in config.worlds:
            for shift in (0.0, config.eval_shift) if config.eval_shift else (0.0,):
                cell = _eval_cell(config, out, policy, train, task, seed, demos, world, shift)
                cells[cell.id] = cell
    return cells


def _tag(seed: int, demos: int) -> str:
    return f"seed{seed}-n{demos}"


def _resources(config: BenchmarkConfig, kind: str) -> dict:
    r = config.resources_for(kind)
    return {"num_cpus": r.num_cpus, "num_gpus": r.num_gpus}


def _collect_cell(config: BenchmarkConfig, out: Path, task: str) -> Cell | None:
    users = [p for p in config.policies if task in config.tasks_of(p)]
    if not users:
        return None
    cameras: list[str] = []
    for policy in users:
        cameras += [c for c in config.cameras_of(policy) if c not in cameras]
    episodes = max(max(config.demo_counts(p, task)) for p in users)
    rmb = out / "data" / task / "rmb"
    workers = max(1, int(config.resources_for("collect").num_cpus))
    stage = collect_stage(
        task,
        rmb,
        episodes,
        cameras,
        config.image_size,
        depth=any(p.depth for p in users),
        workers=workers,
        seed=config.collect_seed,
        extra=(
            "--world-idx",
            *map(str, config.collect_worlds),
            *([f"--random-shift={config.collect_shift}"] if config.collect_shift else []),
            *config.collect_args,
        ),
    )
    return Cell(
        f"collect/{task}",
        "collect",
        stage,
        rmb,
        (),
        out,
        reset=(rmb,),
        launcher=config.launcher,
        **_resources(config, "collect"),
    )


def episode_paths(config: BenchmarkConfig, rmb: Path, task: str, demos: int) -> list[Path]:
    """The first ``demos`` episodes ``rmb-collect`` writes for ``task`` into ``rmb``."""
    collect = CollectConfig(task, rmb, episodes=demos, world_idx=config.collect_worlds)
    worlds = config.collect_worlds
    return [collect.episode_path(i, worlds[i % len(worlds)]) for i in range(demos)]


def _convert_cell(config: BenchmarkConfig, out: Path, key: DatasetKey, collect: Cell) -> Cell:
    dataset = out / "data" / key.task / key.name
    stage = convert_stage(
        episode_paths(config, collect.output, key.task, key.demos),
        dataset,
        f"local/{key.task}_{key.name}",
        cameras=key.cameras,
        depth=key.depth,
        video_codec=config.video_codec,
    )
    return Cell(
        f"convert/{key.task}/{key.name}",
        "convert",
        stage,
        dataset / "meta" / "info.json",
        (collect.id,),
        out,
        reset=(dataset,),
        inputs=tuple(episode_paths(config, collect.output, key.task, key.demos)),
        launcher=config.launcher,
        **_resources(config, "convert"),
    )


def env_inputs(config: BenchmarkConfig, policy: PolicySpec, task: str) -> EnvInputs:
    return EnvInputs(
        task,
        config.cameras_of(policy),
        config.image_size,
        depth=policy.depth,
        episode_length=config.episode_length,
    )


def _train_cell(
    config: BenchmarkConfig,
    out: Path,
    policy: PolicySpec,
    convert: Cell,
    key: DatasetKey,
    seed: int,
) -> Cell:
    task = key.task
    output_dir = out / "train" / task / policy.name / _tag(seed, key.demos)
    curve = config.learning_curve
    spec = TrainSpec(
        policy_type=policy.policy_type,
        policy_args=policy.policy_args,
        steps=policy.steps,
        batch_size=policy.batch_size,
        dataset=convert.output.parent.parent,
        repo_id=f"local/{task}_{key.name}",
        env=env_inputs(config, policy, task),
        output_dir=output_dir,
        seed=seed,
        device=config.device,
        num_workers=policy.num_workers,
        eval_freq=config.eval_freq(policy, task) if key.demos == config.demos else 0,
        eval_episodes=curve.eval_episodes if curve is not None else 1,
    )
    return Cell(
        f"train/{task}/{policy.name}/{_tag(seed, key.demos)}",
        "train",
        train_stage(spec),
        checkpoint_of(output_dir),
        (convert.id,),
        out,
        reset=(output_dir,),  # lerobot-train refuses an existing output directory
        key=(("policy", policy.name), ("task", task), ("seed", seed), ("demos", key.demos)),
        launcher=config.launcher,
        **_resources(config, "train"),
    )


def _eval_cell(
    config: BenchmarkConfig,
    out: Path,
    policy: PolicySpec,
    train: Cell,
    task: str,
    seed: int,
    demos: int,
    world: int,
    shift: float = 0.0,
) -> Cell:
    name = f"world{world}-shift{shift:g}" if shift else f"world{world}"
    output_dir = out / "eval" / task / policy.name / _tag(seed, demos) / name
    stage = eval_stage(
        train.output,
        env_inputs(config, policy, task),
        world,
        config.eval_episodes,
        eval_seed(config, seed, world),
        output_dir,
        device=config.device,
        random_shift=shift,
    )
    return Cell(
        f"eval/{task}/{policy.name}/{_tag(seed, demos)}/{name}",
        "eval",
        stage,
        output_dir / "eval_info.json",
        (train.id,),
        out,
        reset=(output_dir,),
        key=(*train.key, ("world", world), ("shift", shift)),
        launcher=config.launcher,
        **_resources(config, "eval"),
    )
