"""Particle: success criterion, worlds, particle model, stability, determinism, the expert."""

import mujoco
import numpy as np
import pytest

from rmb_lerobot.envs.base import RmbEnv
from rmb_lerobot.envs.registry import compose
from rmb_lerobot.envs.tasks.particle import (
    CASE_HEIGHT,
    GOAL,
    PARTICLE,
    PARTICLE_RADIUS,
    SCOOP,
    SOURCE,
    SOURCE_HALF_SIDE,
    ParticleTask,
    count_in_goal,
)
from rmb_lerobot.envs.workspace import RMB_TABLE

GOAL_CENTRE = ParticleTask().goal_pos  # RMB's: 4 cm below the table top
ON_GOAL_FLOOR = np.array([*GOAL_CENTRE[:2], RMB_TABLE.table.top_z + PARTICLE_RADIUS])


@pytest.fixture(scope="module")
def particle_env():
    env = compose(ParticleTask(), cameras=())
    yield env
    env.close()


def test_three_particles_in_the_goal_count_as_success():
    inside = ON_GOAL_FLOOR + np.array([[0.0, 0.0, 0.0], [0.07, -0.07, 0.0], [-0.05, 0.06, 0.0]])
    assert count_in_goal(inside, GOAL_CENTRE) == 3
    assert count_in_goal(inside[:2], GOAL_CENTRE) == 2


@pytest.mark.parametrize(
    "where",
    [
        np.array([0.085, 0.0, 0.0]),  # beyond the +x wall
        np.array([0.0, -0.085, 0.0]),  # beyond the -y wall
        np.array([0.0, 0.0, CASE_HEIGHT + PARTICLE_RADIUS]),  # on a rim / held above the goal
    ],
)
def test_particles_outside_the_goal_box_do_not_count(where):
    assert count_in_goal((ON_GOAL_FLOOR + where)[None], GOAL_CENTRE) == 0


def _put_particles(env: RmbEnv, positions: np.ndarray) -> None:
    """Move the first ``len(positions)`` particles there (their slide joints hold the offset
    from the body's build position)."""
    model, data = env.sim.model, env.sim.data
    for i, pos in enumerate(positions):
        body = model.body(f"{PARTICLE}_{i}")
        adr = model.jnt_qposadr[body.jntadr[0]]
        data.qpos[adr : adr + 3] = pos - body.pos
    mujoco.mj_forward(model, data)


def test_is_success_reads_the_simulated_particles(particle_env):
    particle_env.reset(seed=0, options={"world_idx": 2})
    task = particle_env.task
    assert not task.is_success(particle_env.sim)
    targets = ON_GOAL_FLOOR + np.array([[-0.03, 0.0, 0.0], [0.0, 0.0, 0.0], [0.03, 0.0, 0.0]])
    _put_particles(particle_env, targets[:2])
    assert task.particle_positions(particle_env.sim)[:2] == pytest.approx(targets[:2])
    assert not task.is_success(particle_env.sim)
    _put_particles(particle_env, targets)
    assert task.is_success(particle_env.sim)


def test_particles_are_non_rotating_spheres_like_mujocos_composite(particle_env):
    model = particle_env.sim.model
    assert ParticleTask().num_particles == 30
    for i in (0, 29):
        body = model.body(f"{PARTICLE}_{i}")
        joints = range(body.jntadr[0], body.jntadr[0] + body.jntnum[0])
        assert [model.jnt_type[j] for j in joints] == [mujoco.mjtJoint.mjJNT_SLIDE] * 3
        assert model.geom_size[body.geomadr[0]][0] == PARTICLE_RADIUS


@pytest.mark.parametrize("world_idx", [0, 5])
def test_worlds_shift_the_source_and_its_particles_only(particle_env, world_idx):
    _, info = particle_env.reset(seed=0, options={"world_idx": world_idx})
    task, data = particle_env.task, particle_env.sim.data
    offset = ParticleTask.world_offsets[world_idx]
    source = ParticleTask().source_nominal_pos + offset
    assert data.body(SOURCE).xpos == pytest.approx(source)
    assert data.geom(f"{SOURCE}_px").xpos[:2] == pytest.approx(
        source[:2] + np.array([SOURCE_HALF_SIDE, 0.0])
    )
    particles = task.particle_positions(particle_env.sim)
    assert particles == pytest.approx(task.particle_start_positions(source))
    assert np.all(np.abs(particles[:, :2] - source[:2]) < 0.115 - PARTICLE_RADIUS)
    assert data.body(GOAL).xpos == pytest.approx(ParticleTask().goal_pos)
    assert data.body(SCOOP).xpos == pytest.approx(ParticleTask().scoop_pos)
    assert not info["is_success"]


def test_worlds_span_rmbs_source_offsets():
    assert ParticleTask.world_offsets[:, 1] == pytest.approx(np.linspace(0.0, 0.2, 6))
    assert not ParticleTask.world_offsets[:, [0, 2]].any()


def test_random_shift_is_bounded_planar_and_seeded(particle_env):
    nominal = ParticleTask().source_nominal_pos + ParticleTask.world_offsets[3]
    positions = []
    for _ in range(2):
        particle_env.reset(seed=7, options={"world_idx": 3, "random_shift": 0.03})
        positions.append(particle_env.sim.data.body(SOURCE).xpos.copy())
    shift = positions[0] - nominal
    assert np.all(np.abs(shift[:2]) <= 0.03) and np.any(np.abs(shift[:2]) > 1e-4)
    assert shift[2] == 0.0
    assert positions[1] == pytest.approx(positions[0])


def test_resting_particles_stay_put_and_fall_asleep(particle_env):
    particle_env.reset(seed=0, options={"world_idx": 1})
    task, model, data = particle_env.task, particle_env.sim.model, particle_env.sim.data
    start = task.particle_positions(particle_env.sim)
    for _ in range(10):
        particle_env.step(particle_env.home_command)
    assert task.particle_positions(particle_env.sim) == pytest.approx(start, abs=1e-3)
    particle_trees = model.body_treeid[[model.body(f"{PARTICLE}_{i}").id for i in range(30)]]
    assert np.all(data.tree_asleep[particle_trees] >= 0)  # out of the solver until touched


# (seed, world) of the random-action rollouts: the invariants must hold for each (one chaotic
# trajectory differs between CPUs). The arm's tool reaches ~11 m/s under random joint targets,
# so a swatted particle may fly fast; a numerically launched one goes 100+ m/s.
RANDOM_ROLLOUTS = [(0, 0), (1, 3), (2, 5), (3, 1)]
MAX_SPEED = 25.0  # m/s


@pytest.mark.parametrize(("seed", "world_idx"), RANDOM_ROLLOUTS)
def test_random_actions_keep_the_simulation_stable(particle_env, random_actions, seed, world_idx):
    env = particle_env
    env.reset(seed=seed, options={"world_idx": world_idx, "random_shift": 0.03})
    model = env.sim.model
    bodies = [model.body(f"{PARTICLE}_{i}") for i in range(30)] + [model.body(SCOOP)]
    # The particles' slide joints and the scoop's linear velocity (the first three).
    linear = np.concatenate([model.jnt_dofadr[b.jntadr[0]] + np.arange(3) for b in bodies])
    fastest = 0.0
    for _ in random_actions(env, steps=300, seed=seed):
        fastest = max(fastest, float(np.abs(env.sim.data.qvel[linear]).max()))
    particles = env.task.particle_positions(env.sim)
    assert fastest < MAX_SPEED
    assert np.all(np.abs(particles[:, :2]) < 2.0)  # still near the table (or on the floor)
    assert np.all(particles[:, 2] > PARTICLE_RADIUS - 0.005)  # none fell through anything
