"""Ring: success criterion on constructed rings, the closed rod, worlds, stability, the expert;
its placement on RMB's xArm7 table."""

import mujoco
import numpy as np
import pytest

from rmb_lerobot.envs.registry import ENVS, compose
from rmb_lerobot.envs.tasks.ring import (
    PEG1,
    PEG2,
    POLE,
    POLE_HEIGHT,
    RING,
    RING_RADIUS,
    SEAM,
    SEGMENT_LENGTH,
    SUCCESS_HEIGHT,
    TUBE_RADIUS,
    RingTask,
    inside_polygon,
    ring_on_pole,
)
from rmb_lerobot.envs.workspace import DUAL_TABLE, RMB_TABLE, XARM_TABLE

POLE_BASE = RingTask().pole_nominal_pos
LYING_Z = RMB_TABLE.table.top_z + TUBE_RADIUS
HOOK_POS = RingTask().hook_pos


@pytest.fixture(scope="module")
def ring_env():
    env = compose(RingTask(), cameras=())
    yield env
    env.close()


def _flat_ring(centre_xy: tuple[float, float], z: float = LYING_Z) -> np.ndarray:
    angles = 2 * np.pi * np.arange(RingTask.num_segments) / RingTask.num_segments
    x = centre_xy[0] + RING_RADIUS * np.cos(angles)
    y = centre_xy[1] + RING_RADIUS * np.sin(angles)
    return np.column_stack([x, y, np.full_like(x, z)])


def test_ring_lying_around_the_pole_is_a_success():
    assert ring_on_pole(_flat_ring((0.03, -0.02)), POLE_BASE)


def test_ring_beside_the_pole_fails():
    assert not ring_on_pole(_flat_ring((0.09, 0.0)), POLE_BASE)


def test_ring_above_the_pole_top_fails():
    top = POLE_BASE[2] + POLE_HEIGHT
    assert not ring_on_pole(_flat_ring((0.0, 0.0), z=top + 0.001), POLE_BASE)
    assert ring_on_pole(_flat_ring((0.0, 0.0), z=top - 0.001), POLE_BASE)


def test_success_height_is_rmbs_pole_top():
    # RMB: pole body origin + 0.08 m, its origin 2 cm below the table: the pole's top.
    assert pytest.approx(POLE_HEIGHT) == SUCCESS_HEIGHT


def test_one_raised_point_fails():
    ring = _flat_ring((0.0, 0.0))
    ring[4, 2] = POLE_BASE[2] + POLE_HEIGHT + 0.01  # tilted, one side above the pole's top
    assert not ring_on_pole(ring, POLE_BASE)


def test_polygon_test_handles_a_concave_ring():
    square_u = np.array([[0, 0], [3, 0], [3, 3], [2, 3], [2, 1], [1, 1], [1, 3], [0, 3]], float)
    assert inside_polygon(square_u, np.array([0.5, 2.0]))
    assert not inside_polygon(square_u, np.array([1.5, 2.0]))  # in the notch


def test_ring_is_a_closed_elastic_rod(ring_env):
    model, data = ring_env.sim.model, ring_env.sim.data
    ring_env.reset(seed=0, options={"world_idx": 0})
    flex = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_FLEX, RING)
    n = RingTask.num_segments
    assert model.flex_dim[flex] == 1 and model.flex_vertnum[flex] == n + 1
    assert model.flex_radius[flex] == TUBE_RADIUS
    assert model.opt.integrator == mujoco.mjtIntegrator.mjINT_DISCRETE
    assert model.joint(f"{RING}_twist").type == mujoco.mjtJoint.mjJNT_HINGE  # rod twist DOFs
    assert model.eq(SEAM).type == mujoco.mjtEq.mjEQ_CONNECT
    vertices = data.flexvert_xpos[model.flex_vertadr[flex] :][: n + 1]
    assert vertices[n] == pytest.approx(vertices[0])  # the seam closes the loop
    edges = np.linalg.norm(np.diff(vertices, axis=0), axis=1)
    assert edges == pytest.approx(SEGMENT_LENGTH)


def test_ring_starts_hanging_on_the_hook(ring_env):
    ring_env.reset(seed=0, options={"world_idx": 2})
    points = ring_env.task.ring_points(ring_env.sim)
    assert points[:, 0] == pytest.approx(HOOK_POS[0])  # in the vertical y-z plane
    assert points.mean(axis=0)[1] == pytest.approx(HOOK_POS[1])
    peg_top = HOOK_POS[2] + 0.01
    assert points[0, 2] > peg_top + TUBE_RADIUS  # the top vertex is above the pegs
    for _ in range(30):  # and the ring stays there
        ring_env.step(ring_env.home_command)
    moved = ring_env.task.ring_points(ring_env.sim) - points
    assert np.abs(moved).max() < 0.005


@pytest.mark.parametrize("world_idx", [0, 5])
def test_worlds_shift_the_pole_only(ring_env, world_idx):
    _, info = ring_env.reset(seed=0, options={"world_idx": world_idx})
    offset = RingTask.world_offsets[world_idx]
    assert ring_env.sim.data.body(POLE).xpos == pytest.approx(POLE_BASE + offset)
    assert ring_env.sim.data.geom(PEG1).xpos[1:] == pytest.approx([-0.13, HOOK_POS[2]])
    assert ring_env.sim.data.geom(PEG2).xpos[1:] == pytest.approx([-0.17, HOOK_POS[2]])
    assert not info["is_success"]


def test_worlds_are_rmbs_pole_offsets():
    assert RingTask.world_offsets[:, 1] == pytest.approx([-0.04, 0.08, 0.08, 0.12, 0.12, 0.24])
    assert RingTask.world_offsets[:, 0] == pytest.approx([0.0, 0.04, -0.04, 0.04, -0.04, 0.0])


def test_random_shift_is_bounded_planar_and_seeded(ring_env):
    nominal = POLE_BASE + RingTask.world_offsets[3]
    positions = []
    for _ in range(2):
        ring_env.reset(seed=7, options={"world_idx": 3, "random_shift": 0.03})
        positions.append(ring_env.sim.data.body(POLE).xpos.copy())
    shift = positions[0] - nominal
    assert np.all(np.abs(shift[:2]) <= 0.03) and np.any(np.abs(shift[:2]) > 1e-4)
    assert shift[2] == 0.0
    assert positions[1] == pytest.approx(positions[0])


# (seed, world) of the random-action rollouts: the invariants must hold for each (one chaotic
# trajectory differs between CPUs). The arm's tool reaches ~11 m/s under random joint targets,
# so a knocked ring may fly off fast; a numerically launched one goes 100+ m/s.
RANDOM_ROLLOUTS = [(0, 0), (1, 3), (2, 5), (3, 1)]
MAX_SPEED = 25.0  # m/s


@pytest.mark.parametrize(("seed", "world_idx"), RANDOM_ROLLOUTS)
def test_random_actions_keep_the_simulation_stable(ring_env, random_actions, seed, world_idx):
    env = ring_env
    env.reset(seed=seed, options={"world_idx": world_idx, "random_shift": 0.03})
    slide = np.concatenate(
        [
            env.sim.model.jnt_dofadr[env.sim.model.body(f"{RING}_{i}").jntadr[0]] + np.arange(3)
            for i in range(RingTask.num_segments + 1)
        ]
    )
    fastest = 0.0
    for _ in random_actions(env, steps=300, seed=seed):
        fastest = max(fastest, float(np.abs(env.sim.data.qvel[slide]).max()))
    points = env.task.ring_points(env.sim)
    assert fastest < MAX_SPEED
    closed = np.vstack([points, points[:1]])
    edges = np.linalg.norm(np.diff(closed, axis=0), axis=1)
    assert edges == pytest.approx(SEGMENT_LENGTH, rel=0.1)  # inextensible, seam closed
    # The arm may knock the ring off the hook and even off the table, but not through a surface.
    assert points[:, 2].min() > 0.5 * TUBE_RADIUS


# ------------------------------------------------------------------ the xArm7's scene


@pytest.fixture(scope="module")
def xarm_env():
    env = ENVS["xarm7_ring"].make(cameras=())
    yield env
    env.close()


def test_xarm_placement_is_rmbs():
    # env_xarm7_ring.xml: hook, pole and ring bodies at (0.2, 0, 0.74) on a table top at 0.74,
    # pegs at (0.1, -0.13/-0.17, 0.25) from there; MujocoXarm7RingEnv: pole offsets along +y.
    task = RingTask(XARM_TABLE)
    assert task.hook_pos == pytest.approx([0.3, -0.15, 0.99])
    assert task.pole_nominal_pos == pytest.approx([0.2, 0.0, 0.74])
    assert task.world_offsets[:, 1] == pytest.approx(np.linspace(0.0, 0.2, 6))
    assert not task.world_offsets[:, [0, 2]].any()
    # RMB's threshold, pole origin + 0.08 m, is 2 cm above the xArm scene's pole top.
    assert task.success_height == pytest.approx(0.08)
    assert task.start_pose("xarm7") == ((0.0, 0.0, 0.0, 0.0, np.pi, np.pi / 2, np.pi),)


def test_the_ur5e_placement_is_unchanged_by_the_table():
    task = RingTask(RMB_TABLE)
    assert task.world_offsets is RingTask.world_offsets
    assert task.success_height == pytest.approx(SUCCESS_HEIGHT)


def test_a_workspace_without_placement_is_refused():
    with pytest.raises(ValueError, match=r"dual_table.*known: table, xarm_table"):
        RingTask(DUAL_TABLE)


def test_xarm_success_height_accepts_a_ring_just_above_the_pole():
    task = RingTask(XARM_TABLE)
    base = task.pole_nominal_pos
    ring = _flat_ring(tuple(base[:2]), z=base[2] + POLE_HEIGHT + 0.015)
    assert ring_on_pole(ring, base, task.success_height)
    assert not ring_on_pole(ring, base)  # above the UR5e scene's threshold (the pole's top)
    assert not ring_on_pole(_flat_ring(tuple(base[:2]), z=base[2] + 0.085), base, 0.08)


@pytest.mark.parametrize(("seed", "world_idx"), [(0, 0), (1, 3), (2, 5)])
def test_xarm_ring_hangs_still_on_its_hook(xarm_env, seed, world_idx):
    env = xarm_env
    env.reset(seed=seed, options={"world_idx": world_idx, "random_shift": 0.03})
    hook = env.task.hook_pos
    assert env.sim.data.geom(PEG1).xpos == pytest.approx([hook[0], -0.13, hook[2]])
    assert env.sim.data.geom(PEG2).xpos == pytest.approx([hook[0], -0.17, hook[2]])
    start = env.task.ring_points(env.sim)
    assert start[:, 0] == pytest.approx(hook[0])  # in the vertical y-z plane through the hook
    assert start[:, 2].min() > XARM_TABLE.table.top_z + 0.05  # hanging clear of the table
    for _ in range(30):
        env.step(env.home_command)
    moved = env.task.ring_points(env.sim) - start
    assert np.abs(moved).max() < 0.005
    assert not env.task.is_success(env.sim)


def test_xarm_wrist_follows_a_step_command(xarm_env):
    """The rod needs the ``discrete`` integrator, where the servos are not implicit: the
    xArm's light wrist still follows a step (its model's armature keeps it stable)."""
    env = xarm_env
    env.reset(seed=0, options={"world_idx": 0})
    command = env.home_command.copy()
    command[6] += 0.5
    for _ in range(25):
        env.step(command)
    assert env.measured_joint_pos()[6] == pytest.approx(command[6], abs=0.01)
