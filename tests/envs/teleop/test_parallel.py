"""Parallel collection: one operator's keys drive three cable envs in different worlds."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rmb_lerobot import keys as K
from rmb_lerobot.envs.registry import entry_for
from rmb_lerobot.envs.teleop.keyboard import KeyboardDevice
from rmb_lerobot.envs.teleop.keys import ScriptedKeySource
from rmb_lerobot.envs.teleop.parallel import lane_seed, lane_world
from rmb_lerobot.envs.teleop.session import TeleopConfig, TeleopSession
from rmb_lerobot.episode import open_episode

# n: standby, n: teleop (recording), 3 x w, n: end, s: save -> steps 1..5 recorded.
SAVE_ONE = [(0, "n"), (1, "n"), (2, "w"), (3, "w"), (4, "w"), (6, "n"), (7, "s")]
RECORDED = 5


class Succeeding:
    """An env whose task reports success on every step (the keep / drop logic is under test,
    not the cable task, which three key presses never solve)."""

    def __init__(self, env):
        self._env = env

    def __getattr__(self, name):
        return getattr(self._env, name)

    def step(self, action):
        obs, reward, terminated, truncated, info = self._env.step(action)
        return obs, reward, terminated, truncated, {**info, "is_success": True}


@pytest.fixture(scope="module")
def envs():
    made = [entry_for("cable").make(cameras=(), depth=False) for _ in range(3)]
    yield made
    for env in made:
        env.close()


def session_for(envs, out: Path, keys, **config) -> TeleopSession:
    return TeleopSession(
        envs[0],
        KeyboardDevice(),
        keys,
        TeleopConfig(out=out, realtime=False, **config),
        parallel_envs=envs[1:],
        log=lambda message: None,
    )


def test_three_envs_record_three_complete_episodes_of_one_demonstration(envs, tmp_path):
    session = session_for(envs, tmp_path, ScriptedKeySource(SAVE_ONE), world_idx=(0, 2, 4))
    result = session.run()
    assert [p.name for p in result.saved] == [
        "MujocoUR5eCable_world0_000.rmb",
        "MujocoUR5eCable_world2_001.rmb",
        "MujocoUR5eCable_world4_002.rmb",
    ]
    assert result.demos == 1 and sorted(p.name for p in tmp_path.iterdir()) == sorted(
        p.name for p in result.saved
    )
    commands = []
    for path, world in zip(result.saved, (0, 2, 4), strict=True):
        with open_episode(path) as ep:
            assert len(ep) == RECORDED and ep.attrs["world_idx"] == world
            commands.append(ep[K.COMMAND_JOINT_POS][:])
            pose = ep[K.MEASURED_EEF_POSE][:]
            # Three W presses moved every env's gripper about 3 cm along world +x (root -x).
            assert pose[-1, 0] - pose[0, 0] < -0.005
    # One joint command per step, the same in every env.
    np.testing.assert_array_equal(commands[0], commands[1])
    np.testing.assert_array_equal(commands[0], commands[2])


def test_save_success_only_keeps_the_envs_that_succeeded(envs, tmp_path):
    lanes = [Succeeding(envs[0]), envs[1], Succeeding(envs[2])]
    session = session_for(lanes, tmp_path, ScriptedKeySource(SAVE_ONE), save_success_only=True)
    result = session.run()
    worlds = [lane_world(None, envs[0].task.num_worlds, 0, k, 3) for k in range(3)]
    assert [p.name for p in result.saved] == [
        f"MujocoUR5eCable_world{worlds[0]}_000.rmb",
        f"MujocoUR5eCable_world{worlds[2]}_002.rmb",
    ]
    assert result.discarded == 1 and result.demos == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(p.name for p in result.saved)


def test_a_demonstration_with_no_success_is_not_counted(envs, tmp_path):
    twice = SAVE_ONE + [(t + 8, key) for t, key in SAVE_ONE]
    session = session_for(
        envs, tmp_path, ScriptedKeySource(twice), save_success_only=True, max_episodes=1
    )
    result = session.run()  # neither demonstration succeeds: max_episodes is never reached
    assert result.saved == [] and result.discarded == 6 and result.demos == 0
    assert list(tmp_path.iterdir()) == []


class InterruptingKeys(ScriptedKeySource):
    """Scripted keys, then Ctrl-C (KeyboardInterrupt) at poll ``at``."""

    def __init__(self, events, at: int):
        super().__init__(events, then=())
        self.at = at

    def poll(self) -> list[str]:
        if self.polls == self.at:
            raise KeyboardInterrupt
        return super().poll()


def test_ctrl_c_leaves_only_complete_episodes(envs, tmp_path):
    events = [*SAVE_ONE, (8, "n"), (9, "n"), (10, "w")]  # the second demonstration records
    session = session_for(envs, tmp_path, InterruptingKeys(events, at=12))
    with pytest.raises(KeyboardInterrupt):
        session.run()
    assert len(session.result.saved) == 3
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        p.name for p in session.result.saved
    )
    for path in session.result.saved:
        with open_episode(path) as ep:
            assert len(ep) == RECORDED


def test_lanes_get_distinct_worlds_and_seeds():
    assert [lane_world((1, 3), 6, demo=1, lane=k, num_lanes=3) for k in range(3)] == [3, 1, 3]
    assert [lane_world(None, 6, demo=1, lane=k, num_lanes=3) for k in range(3)] == [3, 4, 5]
    assert lane_world(None, 6, demo=5, lane=0, num_lanes=1) is None  # one env: seed draws it
    seeds = {lane_seed(7, reset, k, 3) for reset in range(4) for k in range(3)}
    assert len(seeds) == 12 and lane_seed(7, 2, 0, 1) == 9
