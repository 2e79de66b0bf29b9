"""The benchmark grid as a config: a YAML or JSON file, optionally overridden from the command line.

Top-level keys (defaults in brackets)::

    out: outputs/benchmark          # every artefact and result; on a cluster a shared path
    tasks: [insert]                 # any name rmb-collect knows (insert, cabinet_slide, ...)
    policies:                       # name -> spec; a bare list of recipe names works too
      act: {}                       # the recipe of the same name (rmb_lerobot.benchmark.recipes)
      act_front: {recipe: act, cameras: [front], tasks: [insert]}
      tiny_mlp: {type: mlp, steps: 100, batch_size: 8, options: {hidden_dims: [64]}}
    seeds: [0]                      # training seeds (lerobot-train --seed)
    worlds: [0, 1, 2, 3, 4, 5]      # evaluation worlds (lerobot-eval --env.world_idx=K)
    demos: 50                       # expert demos per task
    collect_worlds: [0, 1, 2, 3, 4, 5]   # worlds the demos cycle through
    eval_episodes: 5                # per world
    eval_seed: 1000                 # lerobot-eval --seed = eval_seed + 100 * seed + world
    episode_length: null            # eval step limit (default: the task's)
    image_size: [64, 64]            # width, height of every camera
    cameras: [front, hand]          # default cameras of the policies
    device: cpu                     # --policy.device of training and evaluation
    video_codec: null               # rmb-convert --video-codec (default: rmb-convert's)
    collect_seed: 0
    collect_args: []                # extra rmb-collect arguments (e.g. --cycle-instructions)
    collect_shift: 0.0              # metres: rmb-collect --random-shift, a fresh object shift per
                                    # demo (drawn from collect seeds, disjoint from evaluation's)
    eval_shift: null                # metres: also evaluate every world with
                                    # --env.random_shift=S (placements unseen in training)
    launcher: []                    # a prefix of every cell's command, e.g. [nice, -n, "10"] or
                                    # a container's [apptainer, exec, img.sif]
    resources:                      # Ray resources per cell kind
      collect: {num_cpus: 1}  convert: {num_cpus: 1}  train: {num_cpus: 1, num_gpus: 0}
      eval: {num_cpus: 1}
    retries: 1                      # Ray retries of a cell whose worker process died
    learning_curve: {eval_freq: 250, eval_episodes: 3, policies: [...], tasks: [...]}
    data_size: {demos: [10, 25, 50], policies: [...], tasks: [...]}
    tables:                         # markdown tables and plots (default: one of every policy)
      policies: {title: "...", rows: [mlp, act, diffusion, sarnn]}
      cameras: {rows: {act_front: Front, act: Front+Hand}, tasks: [insert]}

With ``collect_shift`` 0 every demo in world K replays world K's scene, and evaluation in
world K (shift 0) replays it again: a "seen" number. ``eval_shift`` adds an "unseen" one per
world, from evaluation seeds none of the demos used (checked here); the report shows both.

A policy spec takes ``recipe``, ``type`` (LeRobot ``--policy.type``), ``steps``, ``batch_size``,
``options`` (``--policy.KEY=VALUE``, added to the recipe's), ``args`` (raw ``lerobot-train``
arguments), ``cameras``, ``depth``, ``tasks`` (the grid's tasks it runs on) and ``num_workers``.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from rmb_lerobot.benchmark.recipes import RECIPES, Recipe, policy_option_args
from rmb_lerobot.envs.collect import CollectConfig
from rmb_lerobot.envs.registry import entry_for

CELL_KINDS = ("collect", "convert", "train", "eval")


class BenchmarkConfigError(ValueError):
    """A bad benchmark config: the message names the file, the key and what was expected."""


@dataclass(frozen=True)
class Resources:
    """Ray resources one cell asks for (``ray.remote(num_cpus=..., num_gpus=...)``)."""

    num_cpus: float = 1
    num_gpus: float = 0


@dataclass(frozen=True)
class PolicySpec:
    """One row of the grid: a LeRobot policy type with its options, inputs and budget."""

    name: str
    policy_type: str
    policy_args: tuple[str, ...] = ()
    steps: int = 1000
    batch_size: int = 16
    cameras: tuple[str, ...] | None = None  # None: the config's cameras
    depth: bool = False
    tasks: tuple[str, ...] | None = None  # None: every task of the grid
    num_workers: int = 0  # lerobot-train data-loader workers


@dataclass(frozen=True)
class Study:
    """An optional study (learning curve or data size), limited to some policies and tasks."""

    policies: tuple[str, ...] | None = None
    tasks: tuple[str, ...] | None = None
    eval_freq: int = 0  # learning curve: lerobot-train --env_eval_freq
    eval_episodes: int = 3  # learning curve: episodes per periodic evaluation
    demos: tuple[int, ...] = ()  # data size: the demo counts

    def covers(self, policy: str, task: str) -> bool:
        return (self.policies is None or policy in self.policies) and (
            self.tasks is None or task in self.tasks
        )


@dataclass(frozen=True)
class TableSpec:
    """A rendered table: policies as rows (with labels), tasks as columns."""

    name: str
    rows: tuple[tuple[str, str], ...]  # (policy name, row label)
    tasks: tuple[str, ...] | None = None
    title: str = ""


@dataclass(frozen=True)
class BenchmarkConfig:
    out: Path
    tasks: tuple[str, ...]
    policies: tuple[PolicySpec, ...]
    seeds: tuple[int, ...] = (0,)
    worlds: tuple[int, ...] = tuple(range(6))  # parse_config: the worlds every task has
    demos: int = 50
    collect_worlds: tuple[int, ...] = tuple(range(6))
    eval_episodes: int = 5
    eval_seed: int = 1000
    episode_length: int | None = None
    image_size: tuple[int, int] = (64, 64)
    cameras: tuple[str, ...] = ("front", "hand")
    device: str = "cpu"
    video_codec: str | None = None
    collect_seed: int = 0
    collect_args: tuple[str, ...] = ()
    collect_shift: float = 0.0
    eval_shift: float | None = None
    launcher: tuple[str, ...] = ()
    resources: dict[str, Resources] = field(default_factory=dict)
    retries: int = 1
    learning_curve: Study | None = None
    data_size: Study | None = None
    tables: tuple[TableSpec, ...] = ()
    source: str = "<config>"

    def policy(self, name: str) -> PolicySpec:
        return next(p for p in self.policies if p.name == name)

    def tasks_of(self, policy: PolicySpec) -> tuple[str, ...]:
        return tuple(t for t in self.tasks if policy.tasks is None or t in policy.tasks)

    def cameras_of(self, policy: PolicySpec) -> tuple[str, ...]:
        return policy.cameras if policy.cameras is not None else self.cameras

    def demo_counts(self, policy: PolicySpec, task: str) -> tuple[int, ...]:
        """The demo counts trained for (policy, task): the grid's, plus the data-size study's."""
        counts = {self.demos}
        if self.data_size is not None and self.data_size.covers(policy.name, task):
            counts.update(self.data_size.demos)
        return tuple(sorted(counts))

    def eval_freq(self, policy: PolicySpec, task: str) -> int:
        curve = self.learning_curve
        return curve.eval_freq if curve is not None and curve.covers(policy.name, task) else 0

    def resources_for(self, kind: str) -> Resources:
        return self.resources.get(kind, Resources())

    def to_json(self) -> dict[str, Any]:
        """The resolved config (what ran), for ``config.json`` beside the results."""

        def plain(value: Any) -> Any:
            if isinstance(value, Path):
                return str(value)
            if isinstance(value, tuple | list):
                return [plain(v) for v in value]
            if isinstance(value, dict):
                return {k: plain(v) for k, v in value.items()}
            if hasattr(value, "__dataclass_fields__"):
                return {k: plain(getattr(value, k)) for k in value.__dataclass_fields__}
            return value

        return plain(self)


# ----------------------------------------------------------------------------- loading
TOP_KEYS = {
    "out", "tasks", "policies", "seeds", "worlds", "demos", "collect_worlds", "eval_episodes",
    "eval_seed", "episode_length", "image_size", "cameras", "device", "video_codec",
    "collect_seed", "collect_args", "collect_shift", "eval_shift", "launcher", "resources",
    "retries",
    "learning_curve", "data_size", "tables",
}  # fmt: skip
POLICY_KEYS = {
    "recipe", "type", "steps", "batch_size", "options", "args", "cameras", "depth", "tasks",
    "num_workers",
}  # fmt: skip


def read_config_file(path: str | Path) -> dict[str, Any]:
    """The raw mapping in a ``.yaml``/``.yml`` or ``.json`` file."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as error:
        raise BenchmarkConfigError(f"cannot read benchmark config {str(path)!r}: {error}") from None
    try:
        if path.suffix in (".yaml", ".yml"):
            import yaml

            raw = yaml.safe_load(text)
        elif path.suffix == ".json":
            raw = json.loads(text)
        else:
            raise BenchmarkConfigError(
                f"benchmark config {str(path)!r}: expected a .yaml, .yml or .json file"
            )
    except (ValueError, ImportError) as error:
        if isinstance(error, BenchmarkConfigError):
            raise
        raise BenchmarkConfigError(f"benchmark config {str(path)!r}: {error}") from None
    if raw is None:
        raw = {}
    if not isinstance(raw, dict):
        raise BenchmarkConfigError(f"benchmark config {str(path)!r}: expected a mapping at the top")
    return raw


def load_config(
    path: str | Path | None = None, overrides: Mapping[str, Any] | None = None
) -> BenchmarkConfig:
    """Read ``path`` (if given), apply ``overrides`` (top-level keys, e.g. from the command line)
    and check everything; errors are :class:`BenchmarkConfigError` naming file and key.

    Besides top-level keys, ``overrides`` may hold ``only_policies`` (keep these policies),
    ``steps`` and ``batch_size`` (for every policy). Narrowing ``tasks`` or the policies also
    narrows the policies', tables' and studies' lists to what is left.
    """
    raw = read_config_file(path) if path is not None else {}
    source = str(path) if path is not None else "<command line>"
    return parse_config(apply_overrides(raw, overrides or {}, source), source=source)


def apply_overrides(
    raw: Mapping[str, Any], overrides: Mapping[str, Any], source: str = "<config>"
) -> dict[str, Any]:
    """``raw`` with command-line ``overrides`` applied (see :func:`load_config`)."""
    raw = dict(raw)
    overrides = {k: v for k, v in overrides.items() if v is not None}
    steps = overrides.pop("steps", None)
    batch_size = overrides.pop("batch_size", None)
    num_workers = overrides.pop("num_workers", None)
    only = overrides.pop("only_policies", None)
    raw.update(overrides)
    policies = raw.get("policies", ["act"])
    if isinstance(policies, str):
        policies = [policies]
    if isinstance(policies, Sequence):
        policies = {name: {} for name in policies}
    if not isinstance(policies, Mapping):
        return raw  # parse_config reports it
    policies = {name: dict(spec or {}) for name, spec in policies.items()}
    if only:
        unknown = [p for p in only if p not in policies]
        if unknown:
            raise BenchmarkConfigError(
                f"{source}: --policies {' '.join(unknown)}: not in the config's policies "
                f"({', '.join(policies)})"
            )
        policies = {name: spec for name, spec in policies.items() if name in only}
    for spec in policies.values():
        if steps is not None:
            spec["steps"] = steps
        if batch_size is not None:
            spec["batch_size"] = batch_size
        if num_workers is not None:
            spec["num_workers"] = num_workers
    if "tasks" in overrides:
        try:
            keep = {entry_for(t).name for t in _as_list(overrides["tasks"])}
        except ValueError as error:
            raise BenchmarkConfigError(f"{source}: tasks: {error}") from None
        policies = {
            name: spec
            for name, spec in policies.items()
            if _narrow(spec, "tasks", keep) is not False
        }
    for key in ("learning_curve", "data_size"):
        study = raw.get(key)
        if isinstance(study, Mapping):
            study = dict(study)
            if "tasks" in overrides:
                _narrow(study, "tasks", {entry_for(t).name for t in _as_list(overrides["tasks"])})
            if only:
                _narrow(study, "policies", set(policies))
            raw[key] = study
    tables = raw.get("tables")
    if isinstance(tables, Mapping) and (only or "tasks" in overrides):
        narrowed = {}
        for name, spec in tables.items():
            spec = dict(spec or {})
            rows = spec.get("rows")
            if isinstance(rows, Mapping):
                spec["rows"] = {k: v for k, v in rows.items() if k in policies}
            elif isinstance(rows, Sequence) and not isinstance(rows, str):
                spec["rows"] = [r for r in rows if r in policies]
            if "tasks" in overrides:
                keep = {entry_for(t).name for t in _as_list(overrides["tasks"])}
                if _narrow(spec, "tasks", keep) is False:
                    continue
            if spec.get("rows", True):
                narrowed[name] = spec
        raw["tables"] = narrowed or None
    if not policies:
        raise BenchmarkConfigError(
            f"{source}: no policy of the config is left to run on tasks "
            f"{overrides.get('tasks', raw.get('tasks'))} with policies {only or 'all'}"
        )
    raw["policies"] = policies
    return raw


def _as_list(value: Any) -> list:
    return [value] if isinstance(value, str) else list(value)


def _narrow(spec: dict, key: str, keep: set[str]) -> bool | None:
    """Intersect ``spec[key]`` (a list of names, if present) with ``keep``; False if that
    leaves nothing, None if the spec has no such list."""
    if spec.get(key) is None:
        return None
    names = _as_list(spec[key])
    try:
        kept = [n for n in names if (entry_for(n).name if key == "tasks" else n) in keep]
    except ValueError:
        return None  # parse_config reports the bad name
    spec[key] = kept
    return bool(kept) or False


def parse_config(raw: Mapping[str, Any], source: str = "<config>") -> BenchmarkConfig:
    """A checked :class:`BenchmarkConfig` from a raw mapping (see the module docstring)."""
    p = _Parser(source)
    p.keys(raw, TOP_KEYS, "top level")
    tasks = tuple(p.task(t, "tasks") for t in p.str_list(raw.get("tasks", ["insert"]), "tasks"))
    if not tasks:
        p.fail("tasks", "expected at least one task")
    if len(set(tasks)) != len(tasks):
        p.fail("tasks", f"repeated task in {list(tasks)}")
    cameras = tuple(p.str_list(raw.get("cameras", ["front", "hand"]), "cameras"))
    image_size = tuple(p.int_list(raw.get("image_size", [64, 64]), "image_size", minimum=8))
    if len(image_size) != 2:
        p.fail("image_size", f"expected [width, height], got {raw.get('image_size')!r}")
    policies = p.policies(raw.get("policies", ["act"]), tasks)
    # Worlds every task of the grid has (RMB: six per MuJoCo task, five or two in PyBullet).
    num_worlds = min(entry_for(task).num_worlds for task in tasks)
    worlds = tuple(p.int_list(raw.get("worlds", list(range(num_worlds))), "worlds"))
    collect_worlds = tuple(
        p.int_list(raw.get("collect_worlds", list(range(num_worlds))), "collect_worlds")
    )
    for key, values in (("worlds", worlds), ("collect_worlds", collect_worlds)):
        if not values or any(not 0 <= w < num_worlds for w in values):
            p.fail(key, f"expected worlds in 0..{num_worlds - 1}, got {list(values)}")
    seeds = tuple(p.int_list(raw.get("seeds", [0]), "seeds", minimum=0))
    if not seeds or len(set(seeds)) != len(seeds):
        p.fail("seeds", f"expected distinct seeds, got {list(seeds)}")
    episode_length = raw.get("episode_length")
    config = BenchmarkConfig(
        out=Path(p.string(raw.get("out", "outputs/benchmark"), "out")),
        tasks=tasks,
        policies=policies,
        seeds=seeds,
        worlds=worlds,
        demos=p.integer(raw.get("demos", 50), "demos", minimum=1),
        collect_worlds=collect_worlds,
        eval_episodes=p.integer(raw.get("eval_episodes", 5), "eval_episodes", minimum=1),
        eval_seed=p.integer(raw.get("eval_seed", 1000), "eval_seed", minimum=0),
        episode_length=None
        if episode_length is None
        else p.integer(episode_length, "episode_length", minimum=1),
        image_size=(image_size[0], image_size[1]),
        cameras=cameras,
        device=p.string(raw.get("device", "cpu"), "device"),
        video_codec=None
        if raw.get("video_codec") is None
        else p.string(raw["video_codec"], "video_codec"),
        collect_seed=p.integer(raw.get("collect_seed", 0), "collect_seed", minimum=0),
        collect_args=tuple(p.str_list(raw.get("collect_args", []), "collect_args")),
        collect_shift=float(p.number(raw.get("collect_shift", 0.0), "collect_shift")),
        eval_shift=None
        if raw.get("eval_shift") is None
        else float(p.number(raw["eval_shift"], "eval_shift")),
        launcher=tuple(p.str_list(raw.get("launcher", []), "launcher")),
        resources=p.resources(raw.get("resources", {})),
        retries=p.integer(raw.get("retries", 1), "retries", minimum=0),
        learning_curve=p.study(raw.get("learning_curve"), "learning_curve", policies, tasks),
        data_size=p.study(raw.get("data_size"), "data_size", policies, tasks),
        source=source,
    )
    for policy in policies:
        for task in config.tasks_of(policy):
            entry = entry_for(task)
            missing = [c for c in config.cameras_of(policy) if c not in entry.cameras]
            if missing:
                p.fail(
                    f"policies.{policy.name}.cameras",
                    f"{' '.join(missing)}: not a camera of {entry.rmb_env_name} "
                    f"(its cameras: {' '.join(entry.cameras)})",
                )
    if config.eval_shift == 0:
        p.fail("eval_shift", "expected a shift > 0 metres (null: no unseen-shift evaluation)")
    if "--random-shift" in " ".join(config.collect_args):
        p.fail("collect_args", "give the demos' object shift as collect_shift, not --random-shift")
    _check_seeds_disjoint(config, p)
    tables = p.tables(raw.get("tables"), policies, tasks)
    return replace(config, tables=tables)


def collect_seed_range(config: BenchmarkConfig) -> range:
    """Every reset seed ``rmb-collect`` may use: episode k's attempt a resets with
    ``collect_seed + k + a * episodes`` (``envs/collect.py``), for up to the most demos any
    training needs and ``CollectConfig.max_attempts`` attempts."""
    episodes = max(
        max(config.demo_counts(p, t)) for p in config.policies for t in config.tasks_of(p)
    )
    return range(config.collect_seed, config.collect_seed + episodes * CollectConfig.max_attempts)


def eval_seed_range(config: BenchmarkConfig) -> range:
    """Every reset seed ``lerobot-eval`` uses (``--seed`` + episode, per seed and world)."""
    starts = [config.eval_seed + 100 * s + w for s in config.seeds for w in config.worlds]
    return range(min(starts), max(starts) + config.eval_episodes)


def _check_seeds_disjoint(config: BenchmarkConfig, p: _Parser) -> None:
    """With random shifts, a seed both collection and evaluation use would evaluate on a
    placement a demo showed: refuse it rather than report it as unseen."""
    if not config.collect_shift and not config.eval_shift:
        return
    collect, evaluate = collect_seed_range(config), eval_seed_range(config)
    if collect.start < evaluate.stop and evaluate.start < collect.stop:
        p.fail(
            "eval_seed",
            f"evaluation seeds {evaluate.start}..{evaluate.stop - 1} overlap the demos' seeds "
            f"{collect.start}..{collect.stop - 1} (collect_seed, demos x "
            f"{CollectConfig.max_attempts} attempts): with object shifts the evaluation must "
            "not replay a demo's placement; move eval_seed or collect_seed",
        )


class _Parser:
    """Checks raw values; every error names the config file and the key path."""

    def __init__(self, source: str):
        self.source = source

    def fail(self, key: str, message: str):
        raise BenchmarkConfigError(f"{self.source}: {key}: {message}")

    def keys(self, raw: Any, known: set[str], where: str) -> None:
        if not isinstance(raw, Mapping):
            self.fail(where, f"expected a mapping, got {raw!r}")
        unknown = sorted(set(raw) - known)
        if unknown:
            self.fail(where, f"unknown key(s) {unknown}; known: {sorted(known)}")

    def string(self, value: Any, key: str) -> str:
        if not isinstance(value, str | Path) or not str(value):
            self.fail(key, f"expected a non-empty string, got {value!r}")
        return str(value)

    def integer(self, value: Any, key: str, minimum: int | None = None) -> int:
        if isinstance(value, bool) or not isinstance(value, int):
            self.fail(key, f"expected an integer, got {value!r}")
        if minimum is not None and value < minimum:
            self.fail(key, f"expected an integer >= {minimum}, got {value!r}")
        return value

    def number(self, value: Any, key: str) -> float:
        if isinstance(value, bool) or not isinstance(value, int | float) or value < 0:
            self.fail(key, f"expected a number >= 0, got {value!r}")
        return value

    def str_list(self, value: Any, key: str) -> list[str]:
        if isinstance(value, str):
            value = [value]
        if not isinstance(value, Sequence):
            self.fail(key, f"expected a list of strings, got {value!r}")
        return [self.string(v, key) for v in value]

    def int_list(self, value: Any, key: str, minimum: int | None = None) -> list[int]:
        if isinstance(value, int) and not isinstance(value, bool):
            value = [value]
        if not isinstance(value, Sequence) or isinstance(value, str):
            self.fail(key, f"expected a list of integers, got {value!r}")
        return [self.integer(v, key, minimum) for v in value]

    def task(self, name: str, key: str) -> str:
        try:
            return entry_for(name).name
        except ValueError as error:
            self.fail(key, str(error))

    def policies(self, raw: Any, tasks: tuple[str, ...]) -> tuple[PolicySpec, ...]:
        if isinstance(raw, str):
            raw = [raw]
        if isinstance(raw, Sequence):
            raw = {self.string(name, "policies"): None for name in raw}
        if not isinstance(raw, Mapping) or not raw:
            self.fail("policies", f"expected a non-empty mapping or list, got {raw!r}")
        return tuple(self.policy(str(name), spec or {}, tasks) for name, spec in raw.items())

    def policy(self, name: str, spec: Any, tasks: tuple[str, ...]) -> PolicySpec:
        key = f"policies.{name}"
        self.keys(spec, POLICY_KEYS, key)
        if "/" in name or not name.strip():
            self.fail(key, "a policy name must be a non-empty string without '/'")
        recipe_name = spec.get("recipe", None if "type" in spec else name)
        if recipe_name is not None and recipe_name not in RECIPES:
            self.fail(
                f"{key}.recipe",
                f"unknown recipe {recipe_name!r}; known: {sorted(RECIPES)} "
                "(or give 'type' and options yourself)",
            )
        recipe = RECIPES[recipe_name] if recipe_name is not None else None
        if recipe is None:
            recipe = Recipe(self.string(spec["type"], f"{key}.type"))
        options = spec.get("options", {})
        if not isinstance(options, Mapping):
            self.fail(f"{key}.options", f"expected a mapping of option: value, got {options!r}")
        try:
            option_args = policy_option_args(options)
        except ValueError as error:
            self.fail(f"{key}.options", str(error))
        cameras = spec.get("cameras", recipe.cameras)
        policy_tasks = spec.get("tasks")
        if policy_tasks is not None:
            policy_tasks = tuple(
                self.task(t, f"{key}.tasks") for t in self.str_list(policy_tasks, f"{key}.tasks")
            )
            outside = [t for t in policy_tasks if t not in tasks]
            if outside:
                self.fail(f"{key}.tasks", f"{outside} not among the grid's tasks {list(tasks)}")
        depth = spec.get("depth", recipe.depth)
        if not isinstance(depth, bool):
            self.fail(f"{key}.depth", f"expected true or false, got {depth!r}")
        return PolicySpec(
            name=name,
            policy_type=self.string(spec.get("type", recipe.policy_type), f"{key}.type"),
            policy_args=(
                *recipe.policy_args,
                *option_args,
                *self.str_list(spec.get("args", []), f"{key}.args"),
            ),
            steps=self.integer(spec.get("steps", recipe.steps), f"{key}.steps", minimum=1),
            batch_size=self.integer(
                spec.get("batch_size", recipe.batch_size), f"{key}.batch_size", minimum=1
            ),
            cameras=None if cameras is None else tuple(self.str_list(cameras, f"{key}.cameras")),
            depth=depth,
            tasks=policy_tasks,
            num_workers=self.integer(spec.get("num_workers", 0), f"{key}.num_workers", minimum=0),
        )

    def resources(self, raw: Any) -> dict[str, Resources]:
        self.keys(raw, set(CELL_KINDS), "resources")
        out = {}
        for kind, spec in raw.items():
            self.keys(spec, {"num_cpus", "num_gpus"}, f"resources.{kind}")
            out[kind] = Resources(
                num_cpus=self.number(spec.get("num_cpus", 1), f"resources.{kind}.num_cpus"),
                num_gpus=self.number(spec.get("num_gpus", 0), f"resources.{kind}.num_gpus"),
            )
        return out

    def study(
        self, raw: Any, key: str, policies: tuple[PolicySpec, ...], tasks: tuple[str, ...]
    ) -> Study | None:
        if raw is None:
            return None
        known = {"policies", "tasks"} | (
            {"eval_freq", "eval_episodes"} if key == "learning_curve" else {"demos"}
        )
        self.keys(raw, known, key)
        names = {p.name for p in policies}
        study_policies = raw.get("policies")
        if study_policies is not None:
            study_policies = tuple(self.str_list(study_policies, f"{key}.policies"))
            unknown = [p for p in study_policies if p not in names]
            if unknown:
                self.fail(f"{key}.policies", f"{unknown} not among the policies {sorted(names)}")
        study_tasks = raw.get("tasks")
        if study_tasks is not None:
            study_tasks = tuple(
                self.task(t, f"{key}.tasks") for t in self.str_list(study_tasks, f"{key}.tasks")
            )
            outside = [t for t in study_tasks if t not in tasks]
            if outside:
                self.fail(f"{key}.tasks", f"{outside} not among the grid's tasks {list(tasks)}")
        if key == "learning_curve":
            return Study(
                study_policies,
                study_tasks,
                eval_freq=self.integer(raw.get("eval_freq"), f"{key}.eval_freq", minimum=1),
                eval_episodes=self.integer(
                    raw.get("eval_episodes", 3), f"{key}.eval_episodes", minimum=1
                ),
            )
        demos = tuple(self.int_list(raw.get("demos"), f"{key}.demos", minimum=1))
        if not demos:
            self.fail(f"{key}.demos", "expected at least one demo count")
        return Study(study_policies, study_tasks, demos=demos)

    def tables(
        self, raw: Any, policies: tuple[PolicySpec, ...], tasks: tuple[str, ...]
    ) -> tuple[TableSpec, ...]:
        if raw is None:
            rows = tuple((p.name, p.name) for p in policies)
            return (TableSpec("policies", rows, None, "Success rate per policy and task"),)
        if not isinstance(raw, Mapping) or not raw:
            self.fail("tables", f"expected a mapping of table name: spec, got {raw!r}")
        names = {p.name for p in policies}
        tables = []
        for name, spec in raw.items():
            key = f"tables.{name}"
            self.keys(spec, {"rows", "tasks", "title"}, key)
            rows = spec.get("rows", sorted(names))
            if isinstance(rows, Mapping):
                pairs = [(self.string(k, key), self.string(v, key)) for k, v in rows.items()]
            else:
                pairs = [(r, r) for r in self.str_list(rows, f"{key}.rows")]
            unknown = [r for r, _ in pairs if r not in names]
            if unknown:
                self.fail(f"{key}.rows", f"{unknown} not among the policies {sorted(names)}")
            table_tasks = spec.get("tasks")
            if table_tasks is not None:
                table_tasks = tuple(
                    self.task(t, f"{key}.tasks") for t in self.str_list(table_tasks, f"{key}.tasks")
                )
            title = self.string(spec.get("title", name), f"{key}.title")
            tables.append(TableSpec(str(name), tuple(pairs), table_tasks, title))
        return tuple(tables)
