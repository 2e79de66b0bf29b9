"""RMB's fingertip tactile grid: hand-computed contacts on a test pad, then the UR5e's 2F-85 pads
in the Pick env, recorded episodes and converted datasets."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from rmb_lerobot import keys as K
from rmb_lerobot import open_episode
from rmb_lerobot.envs.sensors.tactile import RMB_PITCH, TactileGrid, pads_for

G = 9.81
PAD_TOP = 0.1  # world height of the pad's sensing face (and of its site)
ROW_OFFSETS = np.array([-8, -4, 0, 4, 8]) * 1e-3  # RMB's 5 x 8 grid at 4 mm, along site x
COL_OFFSETS = np.array([-14, -10, -6, -2, 2, 6, 10, 14]) * 1e-3  # along site y


def _pad_world(weights: str = "", site_euler: str = "0 0 0") -> str:
    """A 6 x 6 cm pad whose top face carries the grid's site, on a vertical slide resting on
    its lower limit (held by a joint limit, not by a contact), a welded ``skin`` child body
    beside it, a table to the side, and ``weights`` (bodies) dropped onto them. ``site_euler``
    in degrees (MJCF's default)."""
    return f"""
    <mujoco>
      <option timestep="0.002" cone="elliptic" impratio="10"/>
      <worldbody>
        <geom name="table" type="box" size="0.05 0.05 0.005" pos="0.2 0 {PAD_TOP - 0.005}"/>
        <body name="pad" pos="0 0 {PAD_TOP - 0.005}">
          <joint name="slide" type="slide" axis="0 0 1" range="0 0.01"/>
          <geom name="pad" type="box" size="0.03 0.03 0.005" mass="0.05"/>
          <site name="grid" pos="0 0 0.005" euler="{site_euler}"/>
          <body name="skin" pos="0.08 0 0">
            <geom name="skin" type="box" size="0.01 0.01 0.005" mass="0.01"/>
          </body>
        </body>
        {weights}
      </worldbody>
    </mujoco>"""


def _ball(name: str, x: float, y: float, mass: float, radius: float = 0.004) -> str:
    return f"""<body name="{name}" pos="{x} {y} {PAD_TOP + radius + 0.001}"><freejoint/>
      <geom name="{name}" type="sphere" size="{radius}" mass="{mass}"/></body>"""


def _cube(name: str, x: float, y: float, mass: float) -> str:
    """A 2 mm cube: its four corner contacts lie within 1 mm of (x, y)."""
    return f"""<body name="{name}" pos="{x} {y} {PAD_TOP + 0.002}"><freejoint/>
      <geom name="{name}" type="box" size="0.001 0.001 0.001" mass="{mass}"/></body>"""


def _settle(xml: str, seconds: float = 1.0, push: dict[str, float] | None = None):
    """Compile, let everything come to rest (``push``: extra downward force in N on bodies)."""
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    for body, force in (push or {}).items():
        data.xfrc_applied[model.body(body).id, 2] = -force
    mujoco.mj_step(model, data, nstep=int(seconds / model.opt.timestep))
    return model, data


def _only_cell(grid: np.ndarray) -> tuple[int, int]:
    (rows, cols) = np.nonzero(grid)
    assert len(rows) == 1, f"force spread over cells {list(zip(rows, cols, strict=True))}"
    return int(rows[0]), int(cols[0])


def test_grid_is_rmb_layout_centred_on_the_site():
    model, data = _settle(_pad_world())
    grid = TactileGrid(model, "grid")
    assert grid.shape == (5, 8) and grid.pitch == RMB_PITCH == 0.004
    np.testing.assert_allclose(grid.points[:, 0, 0], ROW_OFFSETS, atol=1e-12)
    np.testing.assert_allclose(grid.points[0, :, 1], COL_OFFSETS, atol=1e-12)
    world = grid.world_points(data)
    np.testing.assert_allclose(world[..., 2], PAD_TOP, atol=1e-3)  # on the pad's face
    np.testing.assert_allclose(world[4, 7, :2], [0.008, 0.014], atol=1e-6)
    assert grid.read(data).shape == (5, 8) and not grid.read(data).any()  # nothing touches


@pytest.mark.parametrize(
    ("shape", "x", "y", "cell"),
    [
        ("ball", 0.004, -0.006, (3, 2)),  # on grid point (3, 2)
        ("ball", -0.0068, 0.0113, (0, 6)),  # nearer (-8, 10) mm than any other point
        ("cube", -0.008, 0.014, (0, 7)),  # the corner point
        ("cube", 0.0005, 0.0015, (2, 4)),  # beside the centre of the 5 x 8 grid
    ],
)
def test_resting_weight_lands_on_the_nearest_cell(shape, x, y, cell):
    mass = 0.2
    make = _ball if shape == "ball" else _cube
    model, data = _settle(_pad_world(make("w", x, y, mass)))
    reading = TactileGrid(model, "grid").read(data)
    assert _only_cell(reading) == cell
    np.testing.assert_allclose(reading.sum(), mass * G, rtol=1e-3)
    # MuJoCo orders a sphere before the pad's box and the cube after it: the reading's sign
    # does not depend on which geom of the contact is the pad's.
    first = {model.geom(int(g)).name for g in data.contact.geom[: data.ncon, 0]}
    assert first == ({"w"} if shape == "ball" else {"pad"})


def test_a_push_adds_to_the_weight():
    mass, push = 0.1, 4.0
    model, data = _settle(_pad_world(_ball("w", 0.0, 0.002, mass)), push={"w": push})
    reading = TactileGrid(model, "grid").read(data)
    assert _only_cell(reading) == (2, 4)
    np.testing.assert_allclose(reading.sum(), mass * G + push, rtol=1e-3)


def test_weights_beyond_the_grid_land_on_its_edge():
    """As in the plugin: no distance cut-off, the nearest (edge) point takes the force."""
    weights = _ball("a", 0.025, -0.025, 0.1) + _ball("b", -0.02, 0.0, 0.3)
    model, data = _settle(_pad_world(weights))
    reading = TactileGrid(model, "grid").read(data)
    np.testing.assert_allclose(reading[4, 0], 0.1 * G, rtol=1e-3)  # corner: +x, -y
    np.testing.assert_allclose(reading[0, 3], 0.3 * G, rtol=1e-3)  # -x edge; y=0 ties to col 3
    np.testing.assert_allclose(reading.sum(), 0.4 * G, rtol=1e-3)


def test_only_the_weld_group_of_the_site_body_counts():
    """A weight on the table beside the pad adds nothing; one on the pad's welded child body
    counts (the plugin's rule: every body rigidly attached, e.g. a finger's pad and link)."""
    weights = (
        _ball("on_pad", 0.0, -0.01, 0.1)
        + _ball("on_table", 0.2, 0.0, 0.5)
        + _ball("on_skin", 0.08, 0.0, 0.2)
    )
    model, data = _settle(_pad_world(weights))
    touching = model.geom_bodyid[data.contact.geom[: data.ncon]]
    pairs = {tuple(sorted(model.body(int(b)).name for b in pair)) for pair in touching}
    assert pairs == {("on_pad", "pad"), ("on_table", "world"), ("on_skin", "skin")}
    reading = TactileGrid(model, "grid").read(data)
    np.testing.assert_allclose(reading.sum(), 0.3 * G, rtol=1e-3)
    np.testing.assert_allclose(reading[4, 3], 0.2 * G, rtol=1e-3)  # skin at +80 mm x: edge
    # Read for the table's weld group instead (the world): only the table's weight.
    world = TactileGrid(model, "grid", body="world").read(data)
    np.testing.assert_allclose(world.sum(), 0.5 * G, rtol=1e-3)


def test_rows_follow_the_site_x_axis_and_the_sign_its_z_axis():
    # Site turned 90 deg about z: its x axis is the world's +y, its y axis the world's -x.
    model, data = _settle(_pad_world(_ball("w", -0.0061, 0.0079, 0.1), site_euler="0 0 90"))
    reading = TactileGrid(model, "grid").read(data)
    assert _only_cell(reading) == (4, 5)  # site frame (7.9, 6.1) mm
    np.testing.assert_allclose(reading.sum(), 0.1 * G, rtol=1e-3)
    # Site turned over (z into the pad): the pad pushes the ball along -z, negative reading.
    model, data = _settle(_pad_world(_ball("w", 0.0, 0.0061, 0.1), site_euler="180 0 0"))
    reading = TactileGrid(model, "grid").read(data)
    assert _only_cell(reading) == (2, 2)  # site y = -6.1 mm
    np.testing.assert_allclose(reading.sum(), -0.1 * G, rtol=1e-3)


def test_bad_names_are_refused():
    model = mujoco.MjModel.from_xml_string(_pad_world())
    with pytest.raises(ValueError, match="no site named 'nope'"):
        TactileGrid(model, "nope")
    with pytest.raises(ValueError, match="no body named 'nobody'"):
        TactileGrid(model, "grid", body="nobody")
    with pytest.raises(ValueError, match="shape"):
        TactileGrid(model, "grid", shape=(0, 8))
    with pytest.raises(ValueError, match=r"'panda' has no tactile pads.*ur5e"):
        pads_for("panda")


# ---------------------------------------------------------------- the UR5e's 2F-85 pads
PADS = (K.LEFT_TACTILE_SENSOR, K.RIGHT_TACTILE_SENSOR)


@pytest.fixture(scope="module")
def tactile_pick():
    """Pick with the fingertip grids, running on past success (through release and retreat)."""
    from rmb_lerobot.envs.registry import entry_for

    env = entry_for("pick").make(cameras=(), tactile=True, terminate_on_success=False)
    yield env
    env.close()


def test_pads_face_each_other_with_rmb_axes(tactile_pick):
    """RMB's sites: +z out of each pad towards the other finger, y along the finger (down, to
    the tip, with the gripper pointing down), x across it."""
    tactile_pick.reset(seed=0)
    data = tactile_pick.sim.data
    left, right = (data.site(f"gripper/{key}") for key in PADS)
    for site, other in ((left, right), (right, left)):
        axes = site.xmat.reshape(3, 3)
        towards = (other.xpos - site.xpos) / np.linalg.norm(other.xpos - site.xpos)
        assert axes[:, 2] @ towards > 0.999
        assert axes[:, 1] @ [0.0, 0.0, -1.0] > 0.99  # home pose: the gripper points down


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_pick_grasp_is_felt_by_both_pads_and_an_open_gripper_feels_nothing(tactile_pick, seed):
    from rmb_lerobot.envs.experts.pick import Phase, PickExpert

    env = tactile_pick
    obs, _ = env.reset(seed=seed, options={"world_idx": seed, "random_shift": 0.03})
    expert = PickExpert(env)
    expert.reset()
    totals: dict[Phase, list[tuple[float, float]]] = {}
    for _ in range(env.task.max_episode_steps):
        action = expert(obs)
        step = env.rmb_step_data(action)
        assert all(step[key].shape == (5, 8) for key in PADS)
        totals.setdefault(expert.phase, []).append(tuple(step[key].sum() for key in PADS))
        if len(totals.get(Phase.RETREAT, ())) == 15:
            break
        obs, _, _, _, info = env.step(action)
    assert info["is_success"], env.task_description
    for approach in (Phase.ABOVE, Phase.DESCEND):  # open, nothing between the fingers
        assert not np.any(totals[approach]), approach
    held = np.array(totals[Phase.LIFT] + totals[Phase.CARRY])  # the 2F-85 grips at ~50 N
    assert held.min() > 20.0 and held.max() < 200.0, held.min()
    assert not np.any(totals[Phase.RETREAT][-5:])  # opened, the object left in the basket


def test_tactile_off_leaves_everything_else_as_it_was(tactile_pick):
    """The sites are markers: the same episode with and without tactile records the same
    values (on one machine), plus the two grids; without it the model has no tactile site."""
    from rmb_lerobot.envs.experts.pick import PickExpert
    from rmb_lerobot.envs.registry import entry_for

    plain = entry_for("pick").make(cameras=(), terminate_on_success=False)
    try:
        assert plain.sim.model.nsite + 2 == tactile_pick.sim.model.nsite
        assert plain.sim.tactile() == {}
        runs = []
        for env in (plain, tactile_pick):
            obs, _ = env.reset(seed=4, options={"world_idx": 4})
            expert, steps = PickExpert(env), []
            expert.reset()
            for _ in range(150):  # through the grasp
                action = expert(obs)
                steps.append(env.rmb_step_data(action))
                obs, *_ = env.step(action)
            runs.append(steps)
        for without, with_tactile in zip(*runs, strict=True):
            assert set(with_tactile) - set(without) == set(PADS)
            for key, value in without.items():
                np.testing.assert_array_equal(with_tactile[key], value, err_msg=key)
        assert any(step[K.LEFT_TACTILE_SENSOR].any() for step in runs[1])
    finally:
        plain.close()


def test_tactile_is_for_robots_with_pads():
    from rmb_lerobot.envs.registry import entry_for

    with pytest.raises(ValueError, match="'panda' has no tactile pads"):
        entry_for("panda_cable").make(cameras=(), tactile=True)


def test_lerobot_env_appends_the_grids_to_the_state():
    from rmb_lerobot.envs.lerobot_config import ENV_CONFIGS, make_lerobot_env

    config = ENV_CONFIGS["rmb_ur5e_pick"](cameras=[], tactile=True)
    assert config.features["agent_pos"].shape == (7 + 2 * 40,)
    assert ENV_CONFIGS["rmb_ur5e_pick"](cameras=[]).features["agent_pos"].shape == (7,)
    env = make_lerobot_env(config.task, **config.gym_kwargs)
    try:
        obs, _ = env.reset(seed=0)
        assert env.observation_space["agent_pos"].shape == (87,)
        assert obs["agent_pos"].shape == (87,) and obs["agent_pos"].dtype == np.float32
        closed = obs["agent_pos"].copy()
        closed[6] = 255.0  # close the empty gripper: the pads press on each other
        for _ in range(30):
            obs, *_ = env.step(closed[:7])
        grids = env.unwrapped.sim.tactile()
        expected = np.concatenate([grids[key].ravel() for key in PADS]).astype(np.float32)
        np.testing.assert_array_equal(obs["agent_pos"][7:], expected)
        assert obs["agent_pos"][7:47].sum() > 1.0 and obs["agent_pos"][47:].sum() > 1.0
    finally:
        env.close()


def test_recorded_episode_and_converted_dataset_carry_the_grids(tmp_path):
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    from rmb_lerobot.cli.collect import main as rmb_collect
    from rmb_lerobot.converters import ConvertOptions, from_lerobot, to_lerobot

    args = ["pick", "--episodes", "1", "--world-idx", "0", "--cameras", "--no-depth"]
    assert rmb_collect([*args, "--out", str(tmp_path / "rmb"), "--tactile"]) == 0
    with open_episode(tmp_path / "rmb" / "MujocoUR5ePick_world0_000.rmb") as episode:
        steps, grids = len(episode), {key: episode[key][:] for key in PADS}
    assert all(g.shape == (steps, 5, 8) and g.any() for g in grids.values())

    state_keys = (K.MEASURED_JOINT_POS, *PADS)  # as RMB's --state_keys selects them
    _, root = to_lerobot(
        [tmp_path / "rmb"],
        output=tmp_path / "dataset",
        options=ConvertOptions(state_keys=state_keys),
        progress=False,
    )
    dataset = LeRobotDataset("local/dataset", root=root)
    names = dataset.meta.features["observation.state"]["names"]
    assert len(names) == 87 and names[7] == "left_tactile_sensor.r0_c0"
    assert names[-1] == "right_tactile_sensor.r4_c7"
    state = np.stack([row.numpy() for row in dataset.hf_dataset["observation.state"]])
    flat = np.concatenate([grids[key].reshape(len(state), -1) for key in PADS], axis=1)
    np.testing.assert_array_equal(state[:, 7:], flat.astype(np.float32))

    # Not selected: each grid stays a feature of its own; back in RMB it is (T, 5, 8) again.
    _, root = to_lerobot([tmp_path / "rmb"], output=tmp_path / "plain", progress=False)
    plain = LeRobotDataset("local/plain", root=root)
    assert plain.meta.features[K.LEFT_TACTILE_SENSOR]["shape"] == (40,)
    (back,) = from_lerobot(root=root, output=tmp_path / "back", progress=False)
    with open_episode(back) as episode:
        for key in PADS:
            np.testing.assert_array_equal(episode[key][:], grids[key].astype(np.float32))
