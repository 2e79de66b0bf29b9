"""The grid config: recipes, overrides, and errors that name the file and the key."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rmb_lerobot.benchmark.config import BenchmarkConfigError, load_config, parse_config
from rmb_lerobot.benchmark.recipes import ACT_CPU_ARGS, RECIPES

GRID_SMALL = Path(__file__).parents[2] / "benchmarks" / "grid_small.yaml"


def test_policies_start_from_their_recipe_and_options_become_policy_flags():
    config = parse_config(
        {
            "tasks": ["MujocoUR5eInsert", "rmb_ur5e_door"],  # any name the registry knows
            "policies": {
                "act": {},
                "act_front": {"recipe": "act", "cameras": ["front"], "tasks": ["insert"]},
                "small": {
                    "type": "mlp",
                    "steps": 10,
                    "options": {"hidden_dims": [64, 64], "pretrained_backbone_weights": None},
                    "args": ["--policy.use_amp=false"],
                },
                "dp3": {},
            },
        }
    )
    assert config.tasks == ("insert", "door")
    act, act_front, small, dp3 = config.policies
    assert act.policy_args == ACT_CPU_ARGS and act.steps == RECIPES["act"].steps
    assert config.cameras_of(act) == ("front", "hand") and config.tasks_of(act) == config.tasks
    assert config.cameras_of(act_front) == ("front",) and config.tasks_of(act_front) == ("insert",)
    assert small.policy_type == "mlp" and small.steps == 10 and small.batch_size == 16
    assert small.policy_args == (
        "--policy.hidden_dims=[64,64]",
        "--policy.pretrained_backbone_weights=null",
        "--policy.use_amp=false",
    )
    assert dp3.depth and config.cameras_of(dp3) == ("front",)
    # Default table: every policy, by name.
    [table] = config.tables
    assert [name for name, _ in table.rows] == ["act", "act_front", "small", "dp3"]


def test_command_line_overrides_narrow_policies_tables_and_studies():
    config = load_config(
        GRID_SMALL,
        {
            "tasks": ["insert"],
            "only_policies": ["act", "act_front", "mlp"],
            "steps": 5,
            "num_workers": 3,
            "seeds": [0, 1],
            "out": "/tmp/x",
        },
    )
    assert config.tasks == ("insert",) and config.seeds == (0, 1)
    assert {p.num_workers for p in config.policies} == {3}
    assert [p.name for p in config.policies] == ["mlp", "act", "act_front"]
    assert {p.steps for p in config.policies} == {5}
    assert config.policy("act").batch_size == 8  # the file's, kept
    rows = {t.name: [r for r, _ in t.rows] for t in config.tables}
    assert rows == {"policies": ["mlp", "act"], "cameras": ["act_front", "act"]}
    assert str(config.out) == "/tmp/x"


def test_grid_small_is_the_issues_grid():
    config = load_config(GRID_SMALL)
    assert config.tasks == ("insert", "door", "cabinet_slide", "cloth")
    assert [p.name for p in config.policies] == [
        "mlp",
        "act",
        "diffusion",
        "sarnn",
        "act_front",
        "act_hand",
    ]
    assert config.seeds == (0,) and config.worlds == tuple(range(6)) and config.demos == 50
    assert config.resources_for("collect").num_cpus == 2


@pytest.mark.parametrize(
    ("raw", "message"),
    [
        ({"polices": ["act"]}, "top level: unknown key(s) ['polices']"),
        ({"tasks": ["nope"]}, "tasks: unknown RMB environment 'nope'"),
        ({"policies": {"x": {}}}, "policies.x.recipe: unknown recipe 'x'"),
        ({"policies": {"act": {"steps": 0}}}, "policies.act.steps: expected an integer >= 1"),
        ({"policies": {"act": {"stesp": 1}}}, "policies.act: unknown key(s) ['stesp']"),
        ({"policies": {"act": {"cameras": ["top"]}}}, "not a camera of MujocoUR5eInsert"),
        ({"policies": {"act": {"tasks": ["door"]}}}, "['door'] not among the grid's tasks"),
        ({"worlds": [6]}, "worlds: expected worlds in 0..5"),
        ({"seeds": [1, 1]}, "seeds: expected distinct seeds"),
        ({"resources": {"train": {"gpus": 1}}}, "resources.train: unknown key(s) ['gpus']"),
        ({"data_size": {"demos": []}}, "data_size.demos: expected at least one demo count"),
        ({"learning_curve": {"eval_freq": 10, "policies": ["mlp"]}}, "['mlp'] not among"),
        ({"tables": {"t": {"rows": ["mlp"]}}}, "tables.t.rows: ['mlp'] not among the policies"),
        ({"policies": {"act": {"options": {"a": {"b": 1}}}}}, "nested option values"),
    ],
)
def test_bad_configs_name_the_file_and_the_key(tmp_path, raw, message):
    path = tmp_path / "grid.json"
    path.write_text(json.dumps(raw))
    with pytest.raises(BenchmarkConfigError) as error:
        load_config(path)
    assert str(error.value).startswith(f"{path}: ")
    assert message in str(error.value)


def test_unreadable_or_foreign_files_are_refused(tmp_path):
    with pytest.raises(BenchmarkConfigError, match="cannot read benchmark config"):
        load_config(tmp_path / "missing.yaml")
    (tmp_path / "grid.toml").write_text("x = 1")
    with pytest.raises(BenchmarkConfigError, match=r"expected a \.yaml, \.yml or \.json file"):
        load_config(tmp_path / "grid.toml")
    (tmp_path / "list.yaml").write_text("- a\n")
    with pytest.raises(BenchmarkConfigError, match="expected a mapping at the top"):
        load_config(tmp_path / "list.yaml")
    with pytest.raises(BenchmarkConfigError, match="--policies sarnn: not in the config"):
        load_config(None, {"policies": ["act"], "only_policies": ["sarnn"]})
