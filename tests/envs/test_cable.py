"""Cable: success criterion on constructed cables, worlds, rod model, stability, the expert."""

from typing import ClassVar

import mujoco
import numpy as np
import pytest

from rmb_lerobot.envs.base import RmbEnv
from rmb_lerobot.envs.experts.cable import CableExpert, Phase
from rmb_lerobot.envs.registry import ENVS, compose
from rmb_lerobot.envs.tasks.cable import (
    CABLE,
    CABLE_ANCHOR,
    CABLE_END,
    CABLE_LENGTH,
    CABLE_RADIUS,
    END_BOX_HALF_SIZE,
    POLE1,
    POLE2,
    POLE_HALF_HEIGHT,
    POLE_SPACING,
    CableTask,
    crosses_between_poles,
    s_shape_routed,
)
from rmb_lerobot.envs.workspace import DUAL_TABLE, RMB_TABLE, XARM_TABLE, Table, Workspace

REST_Z = CableTask().anchor_pos[2]  # cable centre line lying on the table
P1 = CableTask().poles_nominal_pos + np.array([0.0, 0.0, POLE_HALF_HEIGHT])  # pole centres
P2 = P1 + np.array([POLE_SPACING, 0.0, 0.0])
ANCHOR = CableTask().anchor_pos


@pytest.fixture(scope="module")
def cable_env():
    env = compose(CableTask(), cameras=())
    yield env
    env.close()


@pytest.fixture(scope="module")
def robot_env():
    """``robot_env(name)``: the registry's cable env ``name`` (physics only), built once."""
    cache: dict[str, RmbEnv] = {}

    def get(name: str) -> RmbEnv:
        if name not in cache:
            cache[name] = ENVS[name].make(cameras=())
        return cache[name]

    yield get
    for env in cache.values():
        env.close()


def _polyline(*xy: tuple[float, float]) -> np.ndarray:
    return np.array([[x, y, REST_Z] for x, y in xy])


# Down the left of pole 1, up through the gap, over pole 2 and down its far side.
S_SHAPE = _polyline(
    (ANCHOR[0], ANCHOR[1]), (-0.14, 0.06), (-0.075, 0.06), (-0.075, 0.14), (0.0, 0.14), (0.0, 0.03)
)


def test_s_shape_is_a_success():
    assert s_shape_routed(S_SHAPE, S_SHAPE[-1], P1, P2)


def test_a_raised_point_fails():
    raised = S_SHAPE.copy()
    raised[3, 2] = P1[2] + 0.011  # a point above the poles' centre height + 1 cm
    assert not s_shape_routed(raised, raised[-1], P1, P2)
    raised[3, 2] = P1[2] + 0.009
    assert s_shape_routed(raised, raised[-1], P1, P2)


@pytest.mark.parametrize(
    "end",
    [
        (P2[0] - 0.005, P1[1] - 0.06),  # not beyond pole 2
        (P2[0] + 0.05, P1[1] - 0.045),  # not far enough below the pole line
    ],
)
def test_end_outside_the_goal_region_fails(end):
    cable = np.vstack([S_SHAPE[:-1], [[*end, REST_Z]]])
    assert crosses_between_poles(cable, P1, P2)
    assert not s_shape_routed(cable, cable[-1], P1, P2)


def test_cable_around_pole2_instead_of_through_the_gap_fails():
    around = _polyline(
        (ANCHOR[0], ANCHOR[1]), (-0.14, 0.06), (-0.02, 0.06), (-0.02, 0.14), (0.02, 0.14),
        (0.02, 0.03),
    )  # fmt: skip
    assert not crosses_between_poles(around, P1, P2)
    assert not s_shape_routed(around, around[-1], P1, P2)


def test_crossing_the_gap_the_wrong_way_fails():
    reverse = S_SHAPE[::-1].copy()  # the same curve listed from the end: -y through the gap
    assert crosses_between_poles(S_SHAPE, P1, P2)
    assert not crosses_between_poles(reverse, P1, P2)


def _resample(path: np.ndarray, count: int, length: float) -> np.ndarray:
    """``count`` points evenly spaced along the first ``length`` metres of ``path``."""
    cum = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(path, axis=0), axis=1))])
    s = np.linspace(0.0, length, count)
    return np.column_stack([np.interp(s, cum, path[:, k]) for k in range(3)])


def _set_cable(env: RmbEnv, points: np.ndarray) -> None:
    """Put the simulated cable's vertices at ``points`` (the end box follows the last edge)."""
    model, data = env.sim.model, env.sim.data
    n = len(points)
    for i in range(1, n - 2):
        body = model.body(f"{CABLE}_{i}")
        adr = model.jnt_qposadr[body.jntadr[0]]
        data.qpos[adr : adr + 3] = points[i] - body.pos
    direction = points[-1] - points[-2]
    yaw = np.arctan2(direction[1], direction[0])
    data.joint(CABLE_END).qpos[:] = [*points[-1], np.cos(yaw / 2), 0, 0, np.sin(yaw / 2)]
    mujoco.mj_forward(model, data)


def test_is_success_reads_the_simulated_cable(cable_env):
    cable_env.reset(seed=0, options={"world_idx": 1})
    assert not cable_env.task.is_success(cable_env.sim)  # straight at start
    extended = np.vstack([S_SHAPE, [[0.0, -0.2, REST_Z]]])  # long enough to resample 0.48 m
    wanted = _resample(extended, CableTask.num_vertices, CABLE_LENGTH)
    _set_cable(cable_env, wanted)
    assert cable_env.task.cable_points(cable_env.sim) == pytest.approx(wanted)
    assert cable_env.task.is_success(cable_env.sim)


def test_cable_is_an_elastic_rod_on_the_discrete_integrator(cable_env):
    model = cable_env.sim.model
    flex = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_FLEX, CABLE)
    assert model.nflex == 1 and model.flex_dim[flex] == 1
    assert model.flex_vertnum[flex] == CableTask.num_vertices
    assert model.flex_radius[flex] == CABLE_RADIUS
    assert model.opt.integrator == mujoco.mjtIntegrator.mjINT_DISCRETE


@pytest.mark.parametrize("world_idx", [0, 5])
def test_worlds_shift_the_poles_only(cable_env, world_idx):
    _, info = cable_env.reset(seed=0, options={"world_idx": world_idx})
    offset = CableTask.world_offsets[world_idx]
    assert cable_env.sim.data.geom(POLE1).xpos == pytest.approx(P1 + offset)
    assert cable_env.sim.data.geom(POLE2).xpos == pytest.approx(P2 + offset)
    points = cable_env.task.cable_points(cable_env.sim)
    assert points[0] == pytest.approx(ANCHOR)
    assert points[-1] == pytest.approx(ANCHOR - np.array([0.0, CABLE_LENGTH, 0.0]))
    assert not info["is_success"]


@pytest.mark.parametrize(
    ("workspace", "connector_xy", "poles_xy"),
    [
        (RMB_TABLE, (-0.175, 0.2), (-0.1, 0.1)),  # env_ur5e_cable.xml, env_panda_cable.xml
        (DUAL_TABLE, (-0.175, 0.2), (-0.1, 0.1)),  # env_ur5e_dual_cable.xml
        (XARM_TABLE, (-0.08, 0.2), (0.02, 0.1)),  # env_xarm7_cable.xml lines 40 and 49
    ],
)
def test_placement_follows_rmbs_scene_of_each_workspace(workspace, connector_xy, poles_xy):
    task = CableTask(workspace)
    top = workspace.table.top_z
    assert task.anchor_pos == pytest.approx([*connector_xy, top + CABLE_RADIUS])
    assert task.poles_nominal_pos == pytest.approx([*poles_xy, top])


def test_a_workspace_without_a_placement_is_refused():
    elsewhere = Workspace("shelf", Table((0.0, 0.0, 1.0), (0.3, 0.3)), ())
    with pytest.raises(ValueError, match="no placement for workspace 'shelf'"):
        CableTask(elsewhere)


@pytest.mark.parametrize("name", ["xarm7_cable", "panda_cable"])
def test_cable_rests_straight_on_the_robots_table(robot_env, name):
    env = robot_env(name)
    env.reset(seed=0, options={"world_idx": 2})
    for _ in range(30):  # hold the start pose: the cable settles where it was laid
        env.step(env.command.astype(np.float32))
    top = env.task.workspace.table.top_z
    points = env.task.cable_points(env.sim)
    # The last two vertices are clamped in the end box, which is taller than the cable.
    assert points[:-2, 2] == pytest.approx(top + CABLE_RADIUS, abs=0.002)
    assert env.sim.body_pose(CABLE_END)[0][2] == pytest.approx(
        top + END_BOX_HALF_SIZE[2], abs=0.002
    )
    assert points[:, 0] == pytest.approx(env.task.anchor_pos[0], abs=0.002)
    assert points[-1, 1] == pytest.approx(env.task.anchor_pos[1] - CABLE_LENGTH, abs=0.005)


def test_success_criterion_on_the_xarm_table(robot_env):
    env = robot_env("xarm7_cable")
    env.reset(seed=0, options={"world_idx": 1})
    pole1 = env.sim.geom_pose(POLE1)[0]
    anchor = env.task.anchor_pos
    rest_z = anchor[2]

    def around_poles(*offsets: tuple[float, float]) -> np.ndarray:
        """The connector, then points offset from pole 1, then on along -y far enough."""
        xy = [anchor[:2], *(pole1[:2] + np.array(o) for o in offsets)]
        xy.append(xy[-1] + np.array([0.0, -0.3]))
        return np.array([[x, y, rest_z] for x, y in xy])

    # Down the left of pole 1, up through the gap, over pole 2 and down its far side.
    s_shape = around_poles((-0.04, -0.04), (0.025, -0.04), (0.025, 0.04), (0.1, 0.04), (0.1, -0.07))
    _set_cable(env, _resample(s_shape, CableTask.num_vertices, CABLE_LENGTH))
    assert env.task.is_success(env.sim)
    # Around pole 2 instead of through the gap.
    around = around_poles((-0.04, -0.04), (0.08, -0.04), (0.08, 0.04), (0.12, 0.04), (0.12, -0.07))
    _set_cable(env, _resample(around, CableTask.num_vertices, CABLE_LENGTH))
    assert not env.task.is_success(env.sim)


@pytest.mark.parametrize("name", ["cable", "xarm7_cable", "panda_cable"])
def test_arm_joints_are_stiff_enough_for_the_discrete_integrator(robot_env, name):
    env = robot_env(name)
    # RMB's xArm7 wrist has no armature: under the discrete integrator its servo chattered at
    # the force limit and never moved. With the model's armature every joint follows a 0.3 rad
    # step (the Panda's shoulder and elbow sag up to 0.05 rad under gravity, as in RMB).
    env.reset(seed=0)
    arm = env.robot.joint_slices()[0][0]
    start = env.measured_joint_pos()[arm]
    target = env.command.copy()
    target[arm] += 0.3
    for _ in range(25):
        env.step(target.astype(np.float32))
    assert np.all(env.measured_joint_pos()[arm] - start > 0.2)


@pytest.mark.parametrize("name", ["cable", "xarm7_cable", "panda_cable"])
def test_expert_grasps_the_box_with_the_fingers_across_it(robot_env, name):
    # The fingers close along the TCP's y axis, which the eef frames turn by 0 (UR5e),
    # 90 (xArm7) or 45 (Panda) degrees: the grasp must square the fingers on the box's
    # 3 cm width, not twist the box between them.
    env = robot_env(name)
    expert = CableExpert(env)
    env.reset(seed=4, options={"world_idx": 4, "random_shift": 0.03})
    expert.reset()
    yaw0 = expert._box_yaw0
    for _ in range(500):  # the grasp takes 71 (UR5e), 116 (xArm7), 155 (Panda) steps
        if expert.phase is Phase.ROUTE:
            break
        env.step(expert())
    else:
        pytest.fail(f"the expert is still in {expert.phase} after 500 steps, not routing")
    box_rot = env.sim.body_pose(CABLE_END)[1]
    turned = np.arctan2(box_rot[1, 0], box_rot[0, 0]) - yaw0
    assert abs((turned + np.pi) % (2 * np.pi) - np.pi) < np.deg2rad(5)
    tcp_y = env.sim.site_pose(env.robot.arms[0].tcp_frame)[1][:, 1]
    assert abs(tcp_y @ box_rot[:, 1]) > np.cos(np.deg2rad(5))  # fingers along the box's width


def test_panda_expert_turns_within_reach_of_the_connector(robot_env):
    # The Panda's fingertip pads lose the box if the cable is stretched (see robot_tuning).
    env = robot_env("panda_cable")
    expert = CableExpert(env)
    assert expert.max_reach == CableExpert.robot_tuning["panda"]["max_reach"]
    env.reset(seed=5, options={"world_idx": 5, "random_shift": 0.03})  # farthest poles
    expert.reset()
    anchor = env.sim.body_pose(CABLE_ANCHOR)[0]
    turn = expert.plan_route()[: CableExpert.half_circle_points]
    reach = [np.linalg.norm(leg.pos[:2] - anchor[:2]) for leg in turn]
    assert max(reach) <= expert.max_reach * CABLE_LENGTH + 1e-9
    assert CableExpert(robot_env("cable")).max_reach is None  # the UR5e's half circle


def test_robot_tuning_may_only_name_the_experts_settings(robot_env):
    class Misspelt(CableExpert):
        robot_tuning: ClassVar = {"panda": {"max_rech": 1.05}}

    with pytest.raises(AttributeError, match=r"Misspelt.robot_tuning\['panda'\] names 'max_rech'"):
        Misspelt(robot_env("panda_cable"))
    Misspelt(robot_env("cable"))  # other robots are not tuned


def test_worlds_span_rmbs_pole_offsets():
    assert CableTask.world_offsets[:, 0] == pytest.approx(np.linspace(-0.03, 0.12, 6))


def test_random_shift_is_bounded_planar_and_seeded(cable_env):
    nominal = P1 + CableTask.world_offsets[3]
    positions = []
    for _ in range(2):
        cable_env.reset(seed=7, options={"world_idx": 3, "random_shift": 0.03})
        positions.append(cable_env.sim.data.geom(POLE1).xpos.copy())
    shift = positions[0] - nominal
    assert np.all(np.abs(shift[:2]) <= 0.03) and np.any(np.abs(shift[:2]) > 1e-4)
    assert shift[2] == 0.0  # the poles stand on the table
    assert positions[1] == pytest.approx(positions[0])


# (seed, world) of the random-action rollouts: the invariants must hold for each (one chaotic
# trajectory differs between CPUs). The arm's tool reaches ~11 m/s under random joint targets,
# so a flicked cable may move fast; a numerically launched one goes 100+ m/s.
RANDOM_ROLLOUTS = [(0, 0), (1, 3), (2, 5), (3, 1)]
MAX_SPEED = 25.0  # m/s


@pytest.mark.parametrize(("seed", "world_idx"), RANDOM_ROLLOUTS)
def test_random_actions_keep_the_simulation_stable(cable_env, random_actions, seed, world_idx):
    env = cable_env
    env.reset(seed=seed, options={"world_idx": world_idx, "random_shift": 0.03})
    slide = np.concatenate(
        [
            env.sim.model.jnt_dofadr[env.sim.model.body(f"{CABLE}_{i}").jntadr[0]] + np.arange(3)
            for i in range(1, CableTask.num_vertices - 2)
        ]
    )
    fastest = 0.0
    for _ in random_actions(env, steps=300, seed=seed):
        fastest = max(fastest, float(np.abs(env.sim.data.qvel[slide]).max()))
    points = env.task.cable_points(env.sim)
    edges = np.linalg.norm(np.diff(points, axis=0), axis=1)
    spacing = CABLE_LENGTH / (CableTask.num_vertices - 1)
    assert fastest < MAX_SPEED
    assert edges == pytest.approx(spacing, rel=0.1)
    # Not asserted, a known defect of the cable task: in 10 of 18 rollouts of 1000 steps (seeds
    # 0..2 x worlds 0..5) the arm pushes the vertex next to the connector into the 1.5 cm table
    # top, where it stays after the arm has gone home (centre line 1.4 cm below the surface).
    # Once fixed: assert points[:, 2].min() > TABLE_TOP_Z (rmb_lerobot.envs.mujoco.scene) here.
