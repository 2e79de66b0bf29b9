"""The env table: every name (RMB, gymnasium, LeRobot) derives from one entry."""

import dataclasses

import pytest

import rmb_lerobot  # noqa: F401 - registers the gymnasium ids
from rmb_lerobot import keys as K
from rmb_lerobot.converters.plan import robot_type_of
from rmb_lerobot.envs import registry
from rmb_lerobot.envs.experts.base import ScriptedExpert
from rmb_lerobot.envs.registry import ENVS, EnvEntry, entry_for, robot_for_env_attr
from rmb_lerobot.envs.robots import UR5E


def test_names_follow_rmb_and_the_issue():
    insert = ENVS["insert"]
    assert insert.rmb_env_name == "MujocoUR5eInsert"
    assert insert.env_attr == "MujocoUR5eInsertEnv"  # what RMB's recorder writes
    assert insert.gym_id == "rmb_lerobot/MujocoUR5eInsert-v0"
    assert insert.lerobot_type == "rmb_ur5e_insert"
    assert insert.robot_type == "ur5e"
    assert insert.cameras == ("front", "left", "right", "hand")


def test_every_name_derives_from_the_robot_record_and_the_task():
    """Another robot's entry: names from its record, short name prefixed by the robot."""
    xarm7 = dataclasses.replace(UR5E, name="xarm7", rmb_name="Xarm7")
    entry = EnvEntry("mujoco", "ur5e", "cable", "m:Task", "m:Expert")
    with pytest.MonkeyPatch.context() as patch:
        patch.setitem(registry.ROBOTS, "xarm7", xarm7)
        entry = dataclasses.replace(entry, robot="xarm7")
        assert entry.name == "xarm7_cable"
        assert entry.rmb_env_name == "MujocoXarm7Cable"
        assert entry.gym_id == "rmb_lerobot/MujocoXarm7Cable-v0"
        assert entry.lerobot_type == "rmb_xarm7_cable" and entry.robot_type == "xarm7"
    with pytest.raises(ValueError, match="unknown robot 'kuka'"):
        EnvEntry("mujoco", "kuka", "cable", "m:Task", "m:Expert")
    with pytest.raises(ValueError, match="unknown simulator 'gazebo'"):
        EnvEntry("gazebo", "ur5e", "cable", "m:Task", "m:Expert")


def test_env_attributes_map_to_robots_exactly_never_by_substring():
    for entry in ENVS.values():
        assert robot_for_env_attr(entry.env_attr) is UR5E
        assert K.layout_for_env(entry.env_attr) == UR5E.layout == K.UR5E_LAYOUT
        assert robot_type_of(entry.env_attr) == "ur5e"
    # The original RMB's UR5e envs that the registry does not derive.
    for env in ("MujocoUR5eCabinetEnv", "RealUR5eDemoEnv", "IsaacUR5eChainEnv"):
        assert robot_for_env_attr(env) is UR5E and robot_type_of(env) == "ur5e"
    # Lookalikes are not UR5e envs: a dual-arm robot, a name without "Env", other cases.
    for env in ("MujocoUR5eDualCableEnv", "MujocoUR5eCable", "mujocour5ecableenv", "UR5e"):
        assert robot_for_env_attr(env) is None and K.layout_for_env(env) is None
        assert robot_type_of(env) == env  # unknown: the attribute itself
    assert robot_for_env_attr(None) is None and robot_for_env_attr(["MujocoUR5eCableEnv"]) is None


@pytest.mark.parametrize("name", sorted(ENVS))
def test_entry_matches_its_task_and_expert(name):
    entry = ENVS[name]
    task_class = entry.load_task_class()
    assert issubclass(entry.load_expert_class(), ScriptedExpert)
    assert task_class.name == entry.task
    aliases = (entry.name, entry.rmb_env_name, entry.env_attr, entry.gym_id, entry.lerobot_type)
    for alias in aliases:
        assert entry_for(alias) is entry


def test_every_task_module_in_the_package_is_in_the_table():
    from pathlib import Path

    import rmb_lerobot.envs.tasks as tasks

    modules = {p.stem for p in Path(tasks.__file__).parent.glob("*.py")} - {"__init__", "base"}
    assert modules == {entry.task_class.split(":")[0].rsplit(".", 1)[1] for entry in ENVS.values()}


def test_unknown_env_names_list_the_known_ones():
    with pytest.raises(
        ValueError, match=r"unknown RMB environment 'MujocoUR5eFly'.*MujocoUR5eInsert"
    ):
        entry_for("MujocoUR5eFly")
