"""Planning a grid: which cells exist, what each runs, and what it depends on."""

from __future__ import annotations

from rmb_lerobot.benchmark.cells import recorded, write_record
from rmb_lerobot.benchmark.config import parse_config
from rmb_lerobot.benchmark.grid import plan


def config(tmp_path, **extra):
    return parse_config(
        {
            "out": str(tmp_path / "out"),
            "tasks": ["insert", "door"],
            "policies": {
                "act": {},
                "dp3": {},
                "act_front": {"recipe": "act", "cameras": ["front"], "tasks": ["insert"]},
            },
            "seeds": [0, 1],
            "worlds": [0, 1],
            "demos": 4,
            "data_size": {"demos": [2], "policies": ["act"], "tasks": ["insert"]},
            "learning_curve": {"eval_freq": 50, "eval_episodes": 2, "policies": ["act"]},
            "resources": {"train": {"num_cpus": 2, "num_gpus": 0.5}},
            **extra,
        }
    )


def test_cells_cover_the_grid_in_dependency_order(tmp_path):
    cells = plan(config(tmp_path))
    by_kind = {}
    for cid, cell in cells.items():
        by_kind.setdefault(cell.kind, []).append(cid)
        assert all(list(cells).index(u) < list(cells).index(cid) for u in cell.upstream)
        assert cell.output.is_absolute()
    assert by_kind["collect"] == ["collect/insert", "collect/door"]
    assert sorted(by_kind["convert"]) == [
        "convert/door/front_depth_n4",
        "convert/door/front_hand_n4",
        "convert/insert/front_depth_n4",
        "convert/insert/front_hand_n2",  # the data-size study's act on insert
        "convert/insert/front_hand_n4",
        "convert/insert/front_n4",
    ]
    # (act on 2 tasks + dp3 on 2 + act_front on 1 + act with 2 demos on insert) x 2 seeds
    assert len(by_kind["train"]) == 6 * 2
    assert len(by_kind["eval"]) == 6 * 2 * 2
    train = cells["train/insert/act/seed1-n4"]
    assert (train.num_cpus, train.num_gpus) == (2, 0.5)
    assert dict(train.key) == {"policy": "act", "task": "insert", "seed": 1, "demos": 4}


def test_collection_serves_every_policy_of_its_task(tmp_path):
    cells = plan(config(tmp_path))
    collect = cells["collect/insert"].stage.args
    assert "--episodes=4" in collect  # the most any training of the task needs
    cameras = collect[collect.index("--cameras") + 1 : collect.index("--image-size")]
    assert cameras == ["front", "hand"]
    assert "--no-depth" not in collect  # dp3 needs depth
    only_rgb = plan(config(tmp_path, policies=["act"]))["collect/insert"].stage.args
    assert "--no-depth" in only_rgb


def test_a_data_size_dataset_takes_the_first_demos_which_cycle_through_the_worlds(tmp_path):
    cells = plan(config(tmp_path))
    args = cells["convert/insert/front_hand_n2"].stage.args
    episodes = [a.rsplit("/", 1)[-1] for a in args if a.endswith(".rmb")]
    assert episodes == ["MujocoUR5eInsert_world0_000.rmb", "MujocoUR5eInsert_world1_001.rmb"]
    assert cells["convert/insert/front_hand_n2"].upstream == ("collect/insert",)
    depth = cells["convert/insert/front_depth_n4"].stage.args
    assert "--depth" in depth and depth[depth.index("--camera-names") + 1 :][:1] == ["front"]


def test_train_and_eval_commands(tmp_path):
    cells = plan(config(tmp_path))
    out = tmp_path / "out"
    act = cells["train/insert/act/seed1-n4"].stage
    assert act.name == "lerobot-train"
    assert f"--dataset.root={out}/data/insert/front_hand_n4" in act.args
    assert "--seed=1" in act.args and "--env_eval_freq=50" in act.args  # the learning curve
    assert "--eval.n_episodes=2" in act.args
    assert "--env_eval_freq=0" in cells["train/insert/act/seed1-n2"].stage.args  # not n=2
    assert "--env_eval_freq=0" in cells["train/insert/dp3/seed1-n4"].stage.args
    assert "--env.depth=true" in cells["train/door/dp3/seed0-n4"].stage.args
    eval_seeds: dict[tuple, list[str]] = {}
    for cell in cells.values():
        if cell.kind == "eval":
            key = dict(cell.key)
            assert f"--env.world_idx={key['world']}" in cell.stage.args
            assert f"--policy.path={cells[cell.upstream[0]].output}" in cell.stage.args
            seed = next(a for a in cell.stage.args if a.startswith("--seed="))
            eval_seeds.setdefault((key["policy"], key["task"], key["demos"]), []).append(seed)
    # Every (training seed, world) is evaluated on its own object shifts.
    assert all(len(set(seeds)) == len(seeds) == 4 for seeds in eval_seeds.values())


def test_a_collection_serves_later_grids_that_need_no_more_of_it(tmp_path):
    full = plan(config(tmp_path))["collect/insert"]
    full.output.mkdir(parents=True)
    write_record(full, 12.0, {})
    # Fewer policies (fewer cameras, no depth), fewer demos: the same demos serve.
    for narrower in (
        config(tmp_path, policies=["act"]),
        config(tmp_path, policies={"act": {"cameras": ["front"]}}, data_size=None),
        config(tmp_path, demos=3, data_size=None),
    ):
        cell = plan(narrower)["collect/insert"]
        assert cell.command() != full.command()
        done = recorded(cell)
        assert done.ok and done.skipped
    # More demos, another camera or image size: refused, naming what to remove to redo it.
    for wider in (
        config(tmp_path, demos=8),
        config(tmp_path, cameras=["front", "left"]),
        config(tmp_path, image_size=[32, 32]),
    ):
        done = recorded(plan(wider)["collect/insert"])
        assert not done.ok and "was done with another command" in done.error
