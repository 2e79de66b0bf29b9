"""The env table: every name (RMB, gymnasium, LeRobot) derives from one entry."""

import gymnasium as gym
import pytest
from rmb_lerobot.envs.catalog import EXPERTS, TASKS
from rmb_lerobot.envs.registry import ENVS, entry_for

import rmb_lerobot  # noqa: F401 - registers the gymnasium ids


def test_names_follow_rmb_and_the_issue():
    insert = ENVS["insert"]
    assert insert.rmb_env_name == "MujocoUR5eInsert"
    assert insert.gym_id == "rmb_lerobot/MujocoUR5eInsert-v0"
    assert insert.lerobot_type == "rmb_ur5e_insert"


@pytest.mark.parametrize("name", sorted(ENVS))
def test_entry_matches_its_task_and_expert(name):
    entry = ENVS[name]
    task_class = entry.load_task_class()
    assert task_class is TASKS[name] and entry.load_expert_class() is EXPERTS[name]
    assert task_class.rmb_env_name == entry.rmb_env_name
    for alias in (entry.task, entry.rmb_env_name, entry.gym_id, entry.lerobot_type):
        assert entry_for(alias) is entry


def test_every_task_module_in_the_package_is_in_the_table():
    from pathlib import Path

    import rmb_lerobot.envs.tasks as tasks

    modules = {p.stem for p in Path(tasks.__file__).parent.glob("*.py")} - {"__init__", "base"}
    assert modules == {entry.task_class.split(":")[0].rsplit(".", 1)[1] for entry in ENVS.values()}
    assert set(ENVS) == set(TASKS) == set(EXPERTS)


def test_unknown_env_names_list_the_known_ones():
    with pytest.raises(
        ValueError, match=r"unknown RMB environment 'MujocoUR5eFly'.*MujocoUR5eInsert"
    ):
        entry_for("MujocoUR5eFly")


@pytest.mark.parametrize("name", sorted(ENVS))
def test_gymnasium_make_after_importing_the_package(name):
    entry = ENVS[name]
    env = gym.make(entry.gym_id, cameras=())
    try:
        obs, info = env.reset(seed=0, options={"world_idx": 2})
        assert info["world_idx"] == 2 and "agent_pos" in obs
        assert env.spec.id == entry.gym_id
        assert (
            env.get_wrapper_attr("_max_episode_steps") == entry.load_task_class().max_episode_steps
        )
    finally:
        env.close()
