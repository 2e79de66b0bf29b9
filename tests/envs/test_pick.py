"""Pick: instructions, success on constructed states, worlds, layouts, stability and the expert."""

import mujoco
import numpy as np
import pytest

from rmb_lerobot import open_episode
from rmb_lerobot.envs.base import RmbEnv
from rmb_lerobot.envs.collect import CollectConfig, collect
from rmb_lerobot.envs.experts.pick import PickExpert
from rmb_lerobot.envs.lerobot_config import ENV_CONFIGS
from rmb_lerobot.envs.registry import compose
from rmb_lerobot.envs.tasks.pick import (
    BASKETS,
    INSTRUCTIONS,
    OBJECTS,
    PickTask,
    best_grasp_yaw,
    layout_is_clear,
)

BANANA, CRACKER_BOX = OBJECTS[0], OBJECTS[1]
BLUE, BLACK = BASKETS


@pytest.fixture(scope="module")
def pick_env():
    env = compose(PickTask(), cameras=())
    yield env
    env.close()


def _put(env: RmbEnv, obj, basket, offset=(0.0, 0.0, 0.0), speed: float = 0.0) -> None:
    """Teleport ``obj`` upright to the basket floor (plus ``offset``) with a given x speed."""
    joint = env.sim.data.joint(obj.body)
    floor = env.sim.data.body(basket.body).xpos + np.array([0.0, 0.0, basket.floor])
    joint.qpos[:3] = floor + np.asarray(offset)
    joint.qvel[:] = 0.0
    joint.qvel[0] = speed
    mujoco.mj_kinematics(env.sim.model, env.sim.data)


def test_eighteen_instructions_name_every_pair():
    assert len(set(INSTRUCTIONS)) == 18 == len(OBJECTS) * len(BASKETS)
    assert "Put the banana in the blue basket." in INSTRUCTIONS
    assert {b.name for b in BASKETS} == {"blue basket", "black basket"}


@pytest.mark.parametrize("instruction", ["Put the mug in the black basket.", INSTRUCTIONS[0]])
def test_instruction_option_sets_the_task_description(pick_env, instruction):
    pick_env.reset(seed=0, options={"instruction": instruction})
    assert pick_env.task_description == instruction
    assert pick_env.rmb_attrs()["task_desc"] == instruction


def test_instruction_is_drawn_from_the_seed(pick_env):
    drawn = []
    for seed in (*range(12), 3):
        pick_env.reset(seed=seed)
        drawn.append(pick_env.task_description)
    assert drawn[3] == drawn[-1]  # same seed, same instruction
    assert set(drawn) <= set(INSTRUCTIONS) and len(set(drawn)) > 4


def test_giving_the_instruction_keeps_the_seeds_layout(pick_env):
    pick_env.reset(seed=5, options={"random_shift": 0.03})
    free = pick_env.sim.data.qpos.copy()
    pick_env.reset(seed=5, options={"random_shift": 0.03, "instruction": INSTRUCTIONS[7]})
    assert pick_env.sim.data.qpos == pytest.approx(free)


def test_lerobot_vector_env_gives_each_env_its_own_instruction():
    """lerobot-eval reads ``task_description`` from every sub-env at every step."""
    config = ENV_CONFIGS["rmb_ur5e_pick"](cameras=[])
    vec = config.create_envs(n_envs=2)["rmb_ur5e_pick"][0]
    try:
        vec.reset(seed=[0, 1])
        described = vec.call("task_description")
    finally:
        vec.close()
    env = compose(PickTask(), cameras=())
    try:
        expected = []
        for seed in (0, 1):
            env.reset(seed=seed)
            expected.append(env.task_description)
    finally:
        env.close()
    assert list(described) == expected and expected[0] != expected[1]


def test_unknown_instruction_is_rejected(pick_env):
    with pytest.raises(ValueError, match="unknown instruction"):
        pick_env.reset(seed=0, options={"instruction": "Put the cat in the hat."})


@pytest.mark.parametrize(
    ("obj", "basket", "offset", "speed", "expected"),
    [
        (BANANA, BLUE, (0.0, 0.0, 0.0), 0.0, True),  # named object resting in named basket
        (BANANA, BLUE, (0.08, -0.1, 0.0), 0.0, True),  # off-centre, still inside the walls
        (BANANA, BLUE, (0.0, 0.0, 0.0), 0.3, False),  # still moving (e.g. bouncing)
        (BANANA, BLUE, (0.0, 0.0, 0.15), 0.0, False),  # held above the rim
        (BANANA, BLUE, (0.11, 0.0, 0.0), 0.0, False),  # outside the wall
        (BANANA, BLACK, (0.0, 0.0, 0.0), 0.0, False),  # right object, wrong basket
        (CRACKER_BOX, BLUE, (0.0, 0.0, 0.0), 0.0, False),  # wrong object, right basket
    ],
)
def test_success_criterion(pick_env, obj, basket, offset, speed, expected):
    pick_env.reset(seed=0, options={"instruction": "Put the banana in the blue basket."})
    assert not pick_env.task.is_success(pick_env.sim)
    _put(pick_env, obj, basket, offset, speed)
    assert pick_env.task.is_success(pick_env.sim) is expected


@pytest.mark.parametrize("world_idx", [0, 5])
def test_worlds_shift_the_baskets_only(pick_env, world_idx):
    _, info = pick_env.reset(seed=0, options={"world_idx": world_idx})
    shift = PickTask.world_offsets[world_idx]
    assert shift[0] != 0.0 and not shift[1:].any()
    for basket in BASKETS:
        expected = np.array([*basket.pos, 0.0]) + shift
        assert pick_env.sim.data.body(basket.body).xpos[:2] == pytest.approx(expected[:2])
    for obj in OBJECTS:
        assert pick_env.sim.data.body(obj.body).xpos[:2] == pytest.approx(obj.slot)
    assert not info["is_success"]


def test_random_shift_moves_objects_independently_and_is_seeded(pick_env):
    layouts = []
    for _ in range(2):
        pick_env.reset(seed=11, options={"world_idx": 2, "random_shift": 0.03})
        layouts.append(np.array([pick_env.sim.data.body(o.body).xpos.copy() for o in OBJECTS]))
    shifts = layouts[0][:, :2] - np.array([o.slot for o in OBJECTS])
    assert np.all(np.abs(shifts) <= 0.03) and len(np.unique(shifts.round(6), axis=0)) == 9
    assert layouts[0][:, 2] == pytest.approx(layouts[0][0, 2])  # all start on the table
    assert layouts[1] == pytest.approx(layouts[0])
    assert layout_is_clear(layouts[0][:, :2])


def test_a_crowded_layout_is_not_clear():
    positions = np.array([o.slot for o in OBJECTS])
    assert layout_is_clear(positions)
    positions[1] = positions[0] + [0.05, 0.0]  # cracker box against the banana
    assert not layout_is_clear(positions)
    # The banana can then only be grasped if no finger zone hits the box: it cannot.
    assert best_grasp_yaw(0, positions) is None


# (seed, world) of the random-action rollouts: the invariants must hold for each (one chaotic
# trajectory differs between CPUs). The arm's tool reaches ~11 m/s under random joint targets.
RANDOM_ROLLOUTS = [(0, 0), (1, 3), (2, 5), (3, 1)]
MAX_SPEED = 25.0  # m/s: a swatted object may fly fast; a numerically launched one goes 100+


@pytest.mark.parametrize(("seed", "world_idx"), RANDOM_ROLLOUTS)
def test_random_actions_keep_the_simulation_stable(pick_env, random_actions, seed, world_idx):
    env = pick_env
    env.reset(seed=seed, options={"world_idx": world_idx, "random_shift": 0.03})
    fastest = 0.0
    for _ in random_actions(env, steps=300, seed=seed):
        speeds = [np.linalg.norm(env.sim.data.joint(o.body).qvel[:3]) for o in OBJECTS]
        fastest = max(fastest, *speeds)
    heights = [env.sim.data.body(o.body).xpos[2] for o in OBJECTS]
    # Swatted about by the arm (a bottle knocked onto the floor may roll far), never launched.
    assert fastest < MAX_SPEED
    assert min(heights) > -0.005  # nothing sank into the table or the floor


@pytest.mark.parametrize(
    ("seed", "instruction"),
    [(0, "Put the cracker box in the black basket."), (5, "Put the banana in the blue basket.")],
)
def test_expert_puts_the_named_object_in_the_named_basket(pick_env, run_expert, seed, instruction):
    info = run_expert(pick_env, PickExpert, seed, instruction=instruction)
    task = pick_env.task
    assert info["is_success"], (
        f"{instruction}: {pick_env.sim.data.body(task.target_object.body).xpos}"
    )


def test_collect_can_cover_every_instruction_evenly(tmp_path):
    # rmb-collect --cycle-instructions: each episode the next instruction, the worlds cycling
    # alongside (RMB's Pick dataset has the same number of demos per instruction).
    config = CollectConfig(
        "pick", tmp_path, episodes=3, world_idx=(1, 4), cameras=(), cycle_variants=True
    )
    results = list(collect(config))
    descriptions = []
    for result in sorted(results, key=lambda r: r.index):
        with open_episode(result.path) as episode:
            descriptions.append((episode.attrs["task_desc"], episode.attrs["world_idx"]))
    assert descriptions == [(INSTRUCTIONS[0], 1), (INSTRUCTIONS[1], 4), (INSTRUCTIONS[2], 1)]


def test_cycling_instructions_of_a_task_without_any_is_refused(tmp_path):
    config = CollectConfig("insert", tmp_path / "out", episodes=1, cameras=(), cycle_variants=True)
    with pytest.raises(ValueError, match="MujocoUR5eInsert has one variant only"):
        next(collect(config))
    assert not (tmp_path / "out").exists()
