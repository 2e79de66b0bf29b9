"""A robot on a mobile base, end to end through the env core: action, command, record, convert.

The robot is made up here: a point arm (its three joints are the tip's position in the base
frame) with a one-joint gripper and a ``head`` camera, standing on an omnidirectional base that
moves by the velocity ``(vx, vy, wz)`` it is commanded in its own frame. The backend is plain
numpy. What is checked is the contract every mobile robot (HSR, ...) inherits: the base
velocity is the last three numbers of every action mode and of the command, bounded by the
base's limits; ``agent_pos`` and the recorded ``measured_mobile_omni_vel`` are the measured base
velocity in the base frame; ``command_joint_pos`` keeps the joints only; the default conversion
puts the base velocity after the joints in the dataset's state and action.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from rmb_lerobot import keys as K
from rmb_lerobot.converters import ConvertOptions
from rmb_lerobot.converters.plan import plan_conversion
from rmb_lerobot.envs.base import RmbEnv
from rmb_lerobot.envs.experts.base import ScriptedExpert, Waypoint
from rmb_lerobot.envs.lerobot_config import action_dim
from rmb_lerobot.envs.point_arm import PointArmBackend, point_arm_robot
from rmb_lerobot.envs.robots import BodyCamera, MobileBase, Pose
from rmb_lerobot.envs.scene import SceneState
from rmb_lerobot.envs.tasks.base import Task
from rmb_lerobot.envs.workspace import RMB_TABLE
from rmb_lerobot.episode import EpisodeWriter, open_episode

BASE = MobileBase(
    joints=("base_x", "base_y", "base_yaw"),
    frame="base_link",
    max_linear_vel=0.2,
    max_angular_vel=0.5,
)
MOBILE_POINT = point_arm_robot(
    "mobile_point",
    home=(0.3, 0.0, 0.5),
    root_frame="base_link",
    base=BASE,
    body_cameras=(BodyCamera("head", parent="base_link", pose=Pose(pos=(0, 0, 1.0)), fovy=60.0),),
)


class MobileBackend(PointArmBackend):
    """The point arm on a base that moves by its commanded velocity; the tip, in the world,
    is the base's planar pose applied to the arm's joint vector."""

    cameras = ("head",)
    camera_fovy = 60.0

    def __init__(self, task: Task) -> None:
        super().__init__(task, MOBILE_POINT, control_dt=0.1)
        self.base_pose = np.zeros(3)  # x, y, yaw in the world
        self.world_vel = np.zeros(3)  # the base's last velocity in the world frame

    def poses(self) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        x, y, yaw = self.base_pose
        turn = Rotation.from_euler("z", yaw).as_matrix()
        return {"tip": (np.array([x, y, 0.0]) + turn @ self.q[:3], turn)}

    def reset(self, world_offset: np.ndarray, home: np.ndarray) -> None:
        super().reset(world_offset, home)
        self.base_pose, self.world_vel = np.zeros(3), np.zeros(3)

    def step(self) -> None:
        vx, vy, wz = self.target[self.robot.base_slice]
        yaw = self.base_pose[2]
        self.world_vel = np.array(
            [vx * np.cos(yaw) - vy * np.sin(yaw), vx * np.sin(yaw) + vy * np.cos(yaw), wz]
        )
        self.base_pose = self.base_pose + self.world_vel * self.control_dt
        super().step()

    def measured_base_velocity(self) -> np.ndarray:
        """The world velocity turned into the base frame (what RMB's HSR env records)."""
        yaw = self.base_pose[2]
        vx, vy, wz = self.world_vel
        return np.array(
            [vx * np.cos(yaw) + vy * np.sin(yaw), -vx * np.sin(yaw) + vy * np.cos(yaw), wz]
        )

    def world_to_root(self, arm: int, pos: np.ndarray, rot: np.ndarray) -> np.ndarray:
        x, y, yaw = self.base_pose
        local = Rotation.from_euler("z", -yaw).apply(pos - np.array([x, y, 0.0]))
        return np.array([*local, 1.0, 0.0, 0.0, 0.0])


class DriveTask(Task):
    """Drive the base 0.3 m along world x (one world)."""

    name = "drive"
    description = "Drive forward."
    world_offsets = np.zeros((1, 3))
    max_episode_steps = 40

    def is_success(self, scene: SceneState) -> bool:
        return bool(scene.body_pose("tip")[0][0] > 0.6)


def make_env(**kwargs) -> RmbEnv:
    task = DriveTask(RMB_TABLE)
    return RmbEnv(task, MobileBackend(task), render_camera="head", **kwargs)


def test_the_record_says_where_the_base_velocity_goes():
    assert MOBILE_POINT.layout == K.RobotLayout(num_joints=4, mobile_dim=3)
    assert MOBILE_POINT.command_size == 7
    assert MOBILE_POINT.base_slice == slice(4, 7)
    np.testing.assert_array_equal(MOBILE_POINT.home_command(), [0.3, 0.0, 0.5, 0.0, 0, 0, 0])
    assert MOBILE_POINT.cameras == ("head",)
    assert action_dim("joint", MOBILE_POINT.layout) == 7
    assert action_dim("eef_rel", MOBILE_POINT.layout) == 6 + 1 + 3


@pytest.mark.parametrize(("mode", "arm_size"), [("joint", 4), ("eef_abs", 10), ("eef_rel", 7)])
def test_every_action_mode_ends_with_the_bounded_base_velocity(mode, arm_size):
    env = make_env(action_mode=mode, cameras=())
    assert env.action_space.shape == (arm_size + 3,)
    np.testing.assert_allclose(env.action_space.high[arm_size:], [0.2, 0.2, 0.5])
    np.testing.assert_allclose(env.action_space.low[arm_size:], [-0.2, -0.2, -0.5])
    assert env.observation_space["agent_pos"].shape == (4 + 3,)
    env.reset(seed=0)
    action = np.zeros(arm_size + 3)
    if mode == "joint":
        action[:4] = env.home_command[:4]
    elif mode == "eef_abs":
        action[:9] = (0.3, 0.0, 0.5, 1, 0, 0, 0, 1, 0)
    action[arm_size:] = (5.0, -0.1, 0.3)  # vx beyond its bound: clipped to 0.2
    command = env.command_from_action(action)
    assert command.shape == (7,)
    np.testing.assert_allclose(command[4:], [0.2, -0.1, 0.3])
    np.testing.assert_allclose(command[:3], [0.3, 0.0, 0.5], atol=1e-9)  # the arm stays put


def test_base_velocity_is_measured_in_the_base_frame_and_observed():
    env = make_env(cameras=())
    env.reset(seed=0)
    turn = np.array([0.3, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5])
    for _ in range(10):  # turn on the spot by 0.5 rad
        obs, *_ = env.step(turn)
    forward = np.array([0.3, 0.0, 0.0, 0.0, 0.1, 0.0, 0.0])
    obs, *_ = env.step(forward)
    # The base faces 0.5 rad off world x, but its velocity is measured in its own frame.
    np.testing.assert_allclose(obs["agent_pos"][4:], [0.1, 0.0, 0.0], atol=1e-6)
    np.testing.assert_allclose(env.sim.world_vel[:2], 0.1 * np.array([np.cos(0.5), np.sin(0.5)]))


def test_episode_records_rmb_mobile_keys_and_converts_them_after_the_joints(tmp_path):
    env = make_env(cameras=("head",))
    env.reset(seed=0)
    path = tmp_path / "drive.rmb"
    with EpisodeWriter(path, {**env.rmb_attrs(), "demo_name": "drive"}) as writer:
        for vx in (0.1, 0.2, 0.2, 0.2):
            action = np.array([0.3, 0.0, 0.5, 1.0, vx, 0.0, 0.0])
            writer.append(env.rmb_step_data(action))
            env.step(action)
    with open_episode(path) as episode:
        assert episode.attrs[K.ATTR_ENV] == "MujocoMobilePointDriveEnv"
        assert list(episode.camera_names) == ["head"]
        assert episode[K.COMMAND_JOINT_POS].shape == (4, 4)  # joints only
        np.testing.assert_allclose(episode[K.COMMAND_MOBILE_OMNI_VEL][:, 0], [0.1, 0.2, 0.2, 0.2])
        # Measured before each command took effect: at rest, then the previous command.
        np.testing.assert_allclose(episode[K.MEASURED_MOBILE_OMNI_VEL][:, 0], [0, 0.1, 0.2, 0.2])
    plan = plan_conversion([path], ConvertOptions())
    assert plan.schema.state_keys == (K.MEASURED_JOINT_POS, K.MEASURED_MOBILE_OMNI_VEL)
    assert plan.schema.action_keys == (K.COMMAND_JOINT_POS, K.COMMAND_MOBILE_OMNI_VEL)
    joints_only = ConvertOptions(state_keys=(K.MEASURED_JOINT_POS, K.MEASURED_EEF_POSE))
    assert plan_conversion([path], joints_only).schema.state_keys == joints_only.state_keys


class DriveExpert(ScriptedExpert):
    """Holds the tip where it is and drives the base forward: the base part of an expert."""

    def tool_offset(self) -> np.ndarray:
        return np.zeros(3)

    def measured_tool(self) -> np.ndarray:
        return self.scene.site_pose("tip")[0]

    def waypoint(self) -> Waypoint:
        return Waypoint(self.measured_tool(), Rotation.identity(), self.open_gripper)

    def base_velocity(self) -> np.ndarray:
        return np.array([0.2, 0.0, 0.0])


@pytest.mark.parametrize("mode", ["joint", "eef_abs", "eef_rel"])
def test_an_expert_appends_its_base_velocity_in_every_mode(mode):
    env = make_env(action_mode=mode, cameras=())
    obs, info = env.reset(seed=0)
    expert = DriveExpert(env)
    expert.reset()
    for _ in range(env.task.max_episode_steps):
        action = expert(obs)
        assert action.shape == env.action_space.shape
        np.testing.assert_allclose(action[-3:], [0.2, 0.0, 0.0])
        obs, _, terminated, _, info = env.step(action)
        if terminated:
            break
    assert info["is_success"]  # 0.3 m at 0.2 m/s: 15 steps of 0.1 s
