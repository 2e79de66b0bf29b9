"""ALOHA Cable (``aloha_cable``): RMB's ALOHA cable layout, its worlds, the success rule (RMB's
UR5e Cable rule, since RMB's ALOHA Cable has no reward) and the two-arm expert.

The generic promises (start pose, determinism, random actions, expert success in joint and
eef_rel, env checker, LeRobot type) are in ``test_contract.py``.
"""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from rmb_lerobot.envs.base import RmbEnv
from rmb_lerobot.envs.experts.aloha_cable import AlohaCableExpert
from rmb_lerobot.envs.registry import ENVS
from rmb_lerobot.envs.tasks.cable import (
    CABLE,
    CABLE_ANCHOR,
    CABLE_END,
    CABLE_LENGTH,
    CABLE_RADIUS,
    POLE1,
    POLE2,
    CableTask,
)
from rmb_lerobot.envs.workspace import ALOHA_TABLE, RMB_TABLE

NAME = "aloha_cable"
TOP = ALOHA_TABLE.table.top_z
POLES_MID_X = 0.04  # env_aloha_cable.xml: the poles body's x; pole 2 mirrors pole 1 about it


@pytest.fixture(scope="module")
def make_env():
    envs = {}

    def get(mode: str = "joint") -> RmbEnv:
        if mode not in envs:
            envs[mode] = ENVS[NAME].make(cameras=(), action_mode=mode)
        return envs[mode]

    yield get
    for env in envs.values():
        env.close()


def test_layout_is_rmbs_aloha_scene():
    """env_aloha_cable.xml: connector box at (-0.175, 0.25), pole 1 at (-0.08, 0.15), pole 2
    24 cm further along +x; six worlds shifting pole 1 by 0..7.5 cm."""
    task = CableTask(ALOHA_TABLE)
    assert task.anchor_pos == pytest.approx([-0.175, 0.25, TOP + CABLE_RADIUS])
    assert task.poles_nominal_pos == pytest.approx([-0.08, 0.15, TOP])
    assert task.pole_spacing == pytest.approx(0.24)
    assert task.free_connector and task.mirror_poles
    assert task.world_offsets[:, 0] == pytest.approx(0.015 * np.arange(6))
    assert not task.world_offsets[:, 1:].any()
    # The UR5e's layout keeps its fixed connector, 5 cm spacing and worlds.
    ur5e = CableTask(RMB_TABLE)
    assert not ur5e.free_connector and not ur5e.mirror_poles
    assert ur5e.pole_spacing == pytest.approx(0.05)
    assert ur5e.world_offsets is CableTask.world_offsets


@pytest.mark.parametrize("world_idx", range(6))
def test_worlds_close_the_gap_symmetrically(make_env, world_idx):
    """RMB's modify_world: pole 1 moves +1.5 cm per world, pole 2 by the mirror image."""
    env = make_env()
    _, info = env.reset(seed=0, options={"world_idx": world_idx})
    pole1, pole2 = env.sim.geom_pose(POLE1)[0], env.sim.geom_pose(POLE2)[0]
    shift = 0.015 * world_idx
    assert pole1 == pytest.approx([-0.08 + shift, 0.15, TOP + 0.03])
    assert pole2 == pytest.approx([0.16 - shift, 0.15, TOP + 0.03])
    points = env.task.cable_points(env.sim)
    assert points[0] == pytest.approx(env.task.anchor_pos)
    assert points[-1] == pytest.approx(env.task.anchor_pos - [0.0, CABLE_LENGTH, 0.0])
    assert not info["is_success"]


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_random_shift_moves_both_poles_alike(make_env, seed):
    """The random shift moves the poles body: the gap stays the world's (here 18 cm)."""
    env = make_env()
    env.reset(seed=seed, options={"world_idx": 2, "random_shift": 0.03})
    pole1, pole2 = env.sim.geom_pose(POLE1)[0], env.sim.geom_pose(POLE2)[0]
    assert pole2 - pole1 == pytest.approx([0.18, 0.0, 0.0])
    assert pole1[:2] != pytest.approx([-0.05, 0.15])  # the shift did move them
    assert np.abs(pole1[:2] - [-0.05, 0.15]).max() <= 0.03


def test_the_cable_lies_loose_and_stays_put(make_env):
    """RMB's ALOHA cable has a free joint (the UR5e's connector is fixed); held at its start
    pose, the robot leaves it lying where it was laid."""
    env = make_env()
    model = env.sim.model
    assert model.jnt_type[model.body(CABLE_ANCHOR).jntadr[0]] == mujoco.mjtJoint.mjJNT_FREE
    env.reset(seed=0, options={"world_idx": 0})
    start = env.task.cable_points(env.sim).copy()
    for _ in range(30):
        env.step(env.command.astype(np.float32))
    assert env.task.cable_points(env.sim) == pytest.approx(start, abs=0.005)


def _resample(path: np.ndarray, count: int) -> np.ndarray:
    """``count`` points evenly spaced along the first ``CABLE_LENGTH`` metres of ``path``."""
    cum = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(path, axis=0), axis=1))])
    assert cum[-1] >= CABLE_LENGTH - 1e-9
    s = np.linspace(0.0, CABLE_LENGTH, count)
    return np.column_stack([np.interp(s, cum, path[:, k]) for k in range(3)])


def _set_cable(env: RmbEnv, points: np.ndarray) -> None:
    """Put the whole simulated cable (connector box, vertices, end box) at ``points``."""
    model, data = env.sim.model, env.sim.data
    data.joint(CABLE_ANCHOR).qpos[:] = [*points[0], 1.0, 0.0, 0.0, 0.0]
    for i in range(1, len(points) - 2):
        body = model.body(f"{CABLE}_{i}")
        adr = model.jnt_qposadr[body.jntadr[0]]
        data.qpos[adr : adr + 3] = points[i] - body.pos
    direction = points[-1] - points[-2]
    yaw = np.arctan2(direction[1], direction[0])
    data.joint(CABLE_END).qpos[:] = [*points[-1], np.cos(yaw / 2), 0, 0, np.sin(yaw / 2)]
    mujoco.mj_forward(model, data)


# An S through world 5's 9 cm gap (poles at x = -0.005 and 0.085, y = 0.15), 0.48 m long:
# down the left of pole 1, +y through the gap at x = 0.04, over pole 2, down its far side.
S_WORLD5 = [(-0.06, 0.2), (-0.06, 0.11), (0.04, 0.11), (0.04, 0.19), (0.12, 0.19), (0.12, 0.06)]


@pytest.mark.parametrize(
    ("path", "expected"),
    [
        (S_WORLD5, True),
        (S_WORLD5[::-1], False),  # the same curve from the other end: -y through the gap
        # 10 cm to the left: +y outside pole 1, not through the gap, and short of pole 2
        ([(x - 0.1, y) for x, y in S_WORLD5], False),
        # past pole 2 but off to the right at y = 0.13, not 5 cm below the pole line
        ([*S_WORLD5[:-1], (0.12, 0.13), (0.3, 0.13)], False),
    ],
)
def test_success_is_the_ur5e_cable_rule(make_env, path, expected):
    env = make_env()
    env.reset(seed=0, options={"world_idx": 5})
    xyz = np.array([[x, y, TOP + CABLE_RADIUS] for x, y in path])
    points = _resample(xyz, CableTask.num_vertices)
    _set_cable(env, points)
    assert env.task.cable_points(env.sim) == pytest.approx(points)
    assert env.task.is_success(env.sim) is expected
    lifted = points.copy()
    lifted[8, 2] += 0.05  # a point above the pole tops + 1 cm always fails
    _set_cable(env, lifted)
    assert not env.task.is_success(env.sim)


@pytest.mark.parametrize(("mode", "seed"), [("joint", 0), ("joint", 5), ("eef_rel", 4)])
def test_expert_routes_the_cable_with_both_arms(make_env, mode, seed):
    """Worlds 0 (24 cm gap), 5 (9 cm) and 4: the right arm holds the box first, the left arm
    after the handover, each carrying it a good way, and the episode succeeds."""
    env = make_env(mode)
    expert = AlohaCableExpert(env)
    env.reset(seed=seed, options={"world_idx": seed % 6, "random_shift": 0.03})
    expert.reset()
    carried = {arm.arm.name: 0.0 for arm in expert.arms}
    holders: list[str] = []
    last_box = env.sim.body_pose(CABLE_END)[0]
    info = {}
    for _ in range(env.task.max_episode_steps):
        *_, terminated, _, info = env.step(expert())
        box = env.sim.body_pose(CABLE_END)[0]
        for arm in expert.arms:
            closed = env.measured_joint_pos()[arm.gripper_index] < 0.5 * arm.open_gripper
            if closed and np.linalg.norm(arm.measured_tool() - box) < 0.04:
                carried[arm.arm.name] += float(np.linalg.norm(box - last_box))
                if not holders or holders[-1] != arm.arm.name:
                    holders.append(arm.arm.name)
        last_box = box
        if terminated:
            break
    assert info["is_success"]
    assert holders == ["right", "left"]
    assert carried["right"] > 0.3 and carried["left"] > 0.3, carried
