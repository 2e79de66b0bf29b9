"""The env table: every name (RMB, gymnasium, LeRobot) derives from one entry."""

import pytest

import rmb_lerobot  # noqa: F401 - registers the gymnasium ids
from rmb_lerobot import keys as K
from rmb_lerobot.converters.plan import robot_type_of
from rmb_lerobot.envs.registry import ENVS, EnvEntry, entry_for, robot_for_env_attr
from rmb_lerobot.envs.robots import UR5E, robot_for


def test_names_follow_rmb_and_the_issue():
    insert = ENVS["insert"]
    assert insert.rmb_env_name == "MujocoUR5eInsert"
    assert insert.env_attr == "MujocoUR5eInsertEnv"  # what RMB's recorder writes
    assert insert.gym_id == "rmb_lerobot/MujocoUR5eInsert-v0"
    assert insert.lerobot_type == "rmb_ur5e_insert"
    assert insert.robot_type == "ur5e"
    assert insert.cameras == ("front", "left", "right", "hand")


def test_other_robots_names_derive_from_their_records():
    """Another robot's entry: every name from its record, short name prefixed by the robot."""
    xarm7 = ENVS["xarm7_cable"]
    assert xarm7.rmb_env_name == "MujocoXarm7Cable" and xarm7.env_attr == "MujocoXarm7CableEnv"
    assert xarm7.gym_id == "rmb_lerobot/MujocoXarm7Cable-v0"
    assert xarm7.lerobot_type == "rmb_xarm7_cable" and xarm7.robot_type == "xarm7"
    assert ENVS["xarm7_pusht"].env_attr == "MujocoXarm7PushtEnv"  # RMB's spelling of PushT
    assert ENVS["panda_cable"].lerobot_type == "rmb_panda_cable"
    assert ENVS["panda_cable"].cameras == ("front", "left", "right")  # RMB's Panda: no hand camera
    dual = ENVS["ur5e_dual_cable"]
    assert dual.env_attr == "MujocoUR5eDualCableEnv" and dual.robot_type == "ur5e_dual"
    assert dual.lerobot_type == "rmb_ur5e_dual_cable"
    assert dual.cameras == ("front", "left", "right", "rear", "left_hand", "right_hand")
    with pytest.raises(ValueError, match="unknown robot 'kuka'"):
        EnvEntry("mujoco", "kuka", "cable", "m:Task", "m:Expert")
    with pytest.raises(ValueError, match="unknown simulator 'gazebo'"):
        EnvEntry("gazebo", "ur5e", "cable", "m:Task", "m:Expert")


def test_env_attributes_map_to_robots_exactly_never_by_substring():
    for entry in ENVS.values():
        robot = robot_for(entry.robot)
        assert robot_for_env_attr(entry.env_attr) is robot
        assert K.layout_for_env(entry.env_attr) == robot.layout
        assert robot_type_of(entry.env_attr) == entry.robot_type == robot.name
    # The original RMB's envs that the registry does not derive.
    for env in ("MujocoUR5eCabinetEnv", "RealUR5eDemoEnv", "IsaacUR5eChainEnv"):
        assert robot_for_env_attr(env) is UR5E and robot_type_of(env) == "ur5e"
    assert robot_type_of("RealUR5eDualDemoEnv") == "ur5e_dual"
    assert robot_type_of("RealXarm7DemoEnv") == "xarm7"
    # Lookalikes match nothing: a name without "Env", other cases, a robot without a record.
    for env in ("MujocoUR5eCable", "mujocour5ecableenv", "UR5e", "MujocoXarm7DualCableEnv"):
        assert robot_for_env_attr(env) is None and K.layout_for_env(env) is None
        assert robot_type_of(env) == env  # unknown: the attribute itself
    assert robot_for_env_attr(None) is None and robot_for_env_attr(["MujocoUR5eCableEnv"]) is None


@pytest.mark.parametrize("name", sorted(ENVS))
def test_entry_matches_its_task_and_expert(name):
    entry = ENVS[name]
    task_class = entry.load_task_class()
    expert = entry.load_expert_class()  # a policy: reset() per episode, then expert(obs)
    assert all(callable(getattr(expert, name, None)) for name in ("reset", "select_action"))
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
