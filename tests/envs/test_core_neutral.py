"""The env core runs on any backend: a fake one (no simulator) through reset, step and record.

Proof that the core does not assume MuJoCo: a backend written here in plain numpy (a point arm
whose joints follow their command in one step, a fixed "camera" painting the joint vector) runs
``RmbEnv`` in every action mode, its episodes record and read back as RMB episodes, and none of
it (nor importing the package and its registry) loads ``mujoco`` or ``pybullet``.
"""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from rmb_lerobot import keys as K
from rmb_lerobot.envs.base import RmbEnv
from rmb_lerobot.envs.point_arm import PointArmBackend, PointScene, point_arm_robot
from rmb_lerobot.envs.scene import SceneState
from rmb_lerobot.envs.tasks.base import Task
from rmb_lerobot.envs.workspace import RMB_TABLE
from rmb_lerobot.episode import EpisodeWriter, open_episode

POINT_ARM = point_arm_robot("point", home=(0.0, 0.0, 0.5))


class JointScene(PointScene):
    """The point scene, which also answers for the arm's joints (the tip's coordinates)."""

    def joint_position(self, name: str) -> np.ndarray:
        return self.backend.q[["x", "y", "z"].index(name)][None].copy()

    def joint_velocity(self, name: str) -> np.ndarray:
        return np.zeros(1)


class FakeBackend(PointArmBackend):
    """The point arm with a fixed "camera" painting the joint vector, and depth."""

    def __init__(self, task: Task, with_scene: bool = True) -> None:
        super().__init__(task, POINT_ARM, control_dt=0.02)
        self.with_scene = with_scene

    @property
    def scene(self) -> SceneState | None:
        return JointScene(self) if self.with_scene else None

    def render(self, cameras, *, rgb=True, depth=False):
        width, height = self.image_size
        value = np.uint8(np.clip(self.q[0] * 100 + 100, 0, 255))
        images = {c: np.full((height, width, 3), value, np.uint8) for c in cameras}
        depths = {c: np.full((height, width), 1.0, np.float32) for c in cameras} if depth else {}
        return (images if rgb else {}), depths


class ReachTask(Task):
    """Move the tip above x = 0.3 (three worlds that differ in nothing the fake backend sees)."""

    name = "reach"
    description = "Reach forward."
    world_offsets = np.zeros((3, 3))
    max_episode_steps = 10

    def is_success(self, scene: SceneState) -> bool:
        return bool(scene.body_pose("tip")[0][0] > 0.3)


def make_env(**kwargs) -> RmbEnv:
    return RmbEnv(ReachTask(RMB_TABLE), FakeBackend(ReachTask(RMB_TABLE)), **kwargs)


@pytest.mark.parametrize("mode", ["joint", "eef_abs", "eef_rel"])
def test_fake_backend_runs_the_core_in_every_action_mode(mode):
    env = make_env(action_mode=mode, cameras=("front",), depth=True)
    obs, info = env.reset(seed=0, options={"world_idx": 2})
    assert info == {"is_success": False, "world_idx": 2}
    assert obs["pixels"]["front"].shape == (6, 8, 3)
    assert obs["depth"]["front"].dtype == np.uint16
    assert env.metadata["render_fps"] == 50  # from the backend's 0.02 s period
    for _ in range(5):
        if mode == "joint":
            action = np.array([0.5, 0.0, 0.5, 0.0])
        elif mode == "eef_abs":
            action = np.zeros(env.action_space.shape)
            action[:3] = (0.5, 0.0, 0.5)
            action[3:9] = (1, 0, 0, 0, 1, 0)  # identity rotation, 6-D
        else:
            action = np.zeros(env.action_space.shape)
            action[0] = 0.2
        obs, reward, terminated, _, info = env.step(action)
        if terminated:
            break
    assert info["is_success"] and reward == 1.0 and terminated
    assert env.measured_joint_pos()[0] > 0.3


def test_a_backend_without_a_scene_never_succeeds():
    env = RmbEnv(ReachTask(), FakeBackend(ReachTask(), with_scene=False), cameras=())
    env.reset(seed=0)
    _, reward, terminated, _, info = env.step(np.array([0.9, 0.0, 0.5, 0.0]))
    assert (reward, terminated, info["is_success"]) == (0.0, False, False)


def test_worlds_come_from_the_task():
    env = make_env(cameras=())
    worlds = {env.reset(seed=seed)[1]["world_idx"] for seed in range(40)}
    assert worlds == {0, 1, 2}
    with pytest.raises(ValueError, match=r"world_idx must be an integer in 0\.\.2"):
        env.reset(options={"world_idx": 3})


def test_fake_backend_episode_records_and_reads_back(tmp_path):
    env = make_env(cameras=("front",))
    env.reset(seed=1, options={"world_idx": 0})
    path = tmp_path / "reach.rmb"
    with EpisodeWriter(path, {**env.rmb_attrs(), "demo_name": "reach"}) as writer:
        for x in (0.1, 0.2, 0.4):
            action = np.array([x, 0.0, 0.5, 0.0])
            writer.append(env.rmb_step_data(action))
            env.step(action)
    with open_episode(path) as episode:
        assert episode.attrs[K.ATTR_ENV] == "MujocoPointReachEnv"
        np.testing.assert_allclose(episode[K.COMMAND_JOINT_POS][:, 0], [0.1, 0.2, 0.4])
        np.testing.assert_allclose(episode[K.TIME], [0.0, 0.02, 0.04])
        assert episode[K.rgb_image_key("front")].shape == (3, 6, 8, 3)


def test_importing_the_core_loads_no_simulator():
    code = (
        "import os, sys\n"
        "for var in ('MUJOCO_GL', 'PYOPENGL_PLATFORM'): os.environ.pop(var, None)\n"
        "import rmb_lerobot, rmb_lerobot.envs.base, rmb_lerobot.envs.registry\n"
        "import rmb_lerobot.envs.experts.base\n"
        "from rmb_lerobot.envs.registry import ENVS\n"
        "[entry.load_task_class()(entry.workspace) for entry in ENVS.values()]\n"
        "loaded = sorted(m for m in ('mujoco', 'pybullet') if m in sys.modules)\n"
        "assert not loaded, loaded\n"
        "assert 'MUJOCO_GL' not in os.environ, os.environ['MUJOCO_GL']\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True, timeout=120)


def test_a_missing_simulator_names_its_extra(monkeypatch):
    import importlib.util

    from rmb_lerobot.envs.simulators import SIMULATORS

    real = importlib.util.find_spec
    monkeypatch.setattr(
        importlib.util, "find_spec", lambda name, *a: None if name == "pybullet" else real(name)
    )
    with pytest.raises(ImportError, match=r"pip install 'lerobot_env_rmb\[pybullet\]'"):
        SIMULATORS["pybullet"].backend_class()
