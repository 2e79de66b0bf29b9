"""The PyBullet backend behind the env core: RMB's TACTO timing, cameras, tactile images, state.

Built through the registry like every env (TactoSawyerGrasp); task-specific behaviour is in
``test_tacto_grasp.py`` (and the Insert / Spoon files).
"""

from __future__ import annotations

import numpy as np
import pytest

from rmb_lerobot import keys as K
from rmb_lerobot.envs.registry import ENVS, compose
from rmb_lerobot.envs.tasks.tacto_grasp import TactoGraspTask
from rmb_lerobot.envs.workspace import TACTO_FLOOR, TACTO_SPOON_FLOOR
from rmb_lerobot.pointcloud import depth_to_points, transform_points

GRASP = ENVS["pybullet_sawyer_grasp"]
CAMERAS = ("front", "tactile_left", "tactile_right")


@pytest.fixture(scope="module")
def env():
    env = GRASP.make(
        cameras=CAMERAS, image_size=(64, 48), tactile_size=(40, 30), depth=True, renderer="tiny"
    )
    yield env
    env.close()


def test_names_and_rate_follow_rmbs_tacto_envs(env):
    assert (GRASP.rmb_env_name, GRASP.gym_id) == (
        "TactoSawyerGrasp",
        "rmb_lerobot/TactoSawyerGrasp-v0",
    )
    assert GRASP.lerobot_type == "rmb_pybullet_sawyer_grasp"
    assert env.control_dt == pytest.approx(0.03)  # 6 x 0.005 s
    assert env.metadata["render_fps"] == GRASP.fps == 33
    assert env.available_cameras == CAMERAS


def test_observation_holds_cameras_tactile_images_and_depth(env):
    obs, _ = env.reset(seed=0)
    assert obs["pixels"]["front"].shape == (48, 64, 3)
    assert (
        obs["pixels"]["tactile_left"].shape == obs["pixels"]["tactile_right"].shape == (30, 40, 3)
    )
    assert set(obs["depth"]) == {"front"}  # tactile sensors have no depth
    assert env.observation_space.contains(obs)
    attrs = env.rmb_attrs()
    assert attrs[K.ATTR_CAMERA_NAMES] == ["front"]
    assert attrs[K.ATTR_RGB_TACTILE_NAMES] == ["tactile_left", "tactile_right"]
    assert attrs[K.fovy_attr("front")] == 60.0
    step = env.rmb_step_data()
    assert step[K.rgb_image_key("tactile_left")].shape == (30, 40, 3)


def test_depth_fovy_and_camera_pose_put_the_floor_at_z_0(env):
    """The bottom-left corner of the front view sees the floor: back-projected with the
    recorded fovy and camera pose (what DP3's point clouds use), it lands at z = 0 within half
    a pixel's footprint (PyBullet samples half a pixel off the pinhole's pixel centres: +5 mm
    at 64 x 48 here, +2 mm at 160 x 120, +0.5 mm at 640 x 480, measured)."""
    env.reset(seed=0)
    _, depth = env.sim.render(["front"], rgb=False, depth=True)
    corner = np.full_like(depth["front"], np.inf)
    corner[-6:, :6] = depth["front"][-6:, :6]
    points, _ = depth_to_points(corner, env.fovy("front"))
    world = transform_points(points, matrix=env.sim.camera_pose("front"))
    assert len(world) == 36 and np.all(np.abs(world[:, 2]) < 0.008), world[:, 2]


@pytest.mark.parametrize("workspace", [TACTO_FLOOR, TACTO_SPOON_FLOOR])
def test_workspace_cameras_are_the_pybullet_views(workspace):
    """The neutral workspace records (position, look-at) and the backend's orbit parameters
    describe the same camera."""
    from rmb_lerobot.envs.pybullet.backend import CAMERAS
    from rmb_lerobot.envs.pybullet.camera import opencv_pose

    for scene_camera, spec in zip(workspace.cameras, CAMERAS[workspace.name], strict=True):
        pose = opencv_pose(spec)
        np.testing.assert_allclose(pose[:3, 3], scene_camera.pos, atol=1e-6)
        forward = np.subtract(scene_camera.lookat, scene_camera.pos)
        np.testing.assert_allclose(pose[:3, 2], forward / np.linalg.norm(forward), atol=1e-6)
        assert spec.fovy == scene_camera.fovy


def test_home_state_reads_as_rmb_records_it(env):
    obs, _ = env.reset(seed=0)
    arm = env.robot.arms[0]
    np.testing.assert_allclose(obs["agent_pos"][:7], arm.home, atol=1e-6)
    assert obs["agent_pos"][7] == pytest.approx(0.02, abs=1e-6)  # mean |finger| = g
    assert env.measured_joint_vel()[7] == 0.0
    wrench = env.measured_wrench()
    assert wrench.shape == (6,) and np.all(np.isfinite(wrench))
    # The eef pose RMB records is FK of the joints; it agrees with the simulated link frame.
    pos, rot = env.sim.scene.site_pose(arm.eef_frame)
    np.testing.assert_allclose(
        env.eef_pose(env.measured_joint_pos())[:3], pos - np.array(arm.mount.pos), atol=1e-5
    )
    tcp, _ = env.sim.scene.site_pose(arm.tcp_frame)
    assert np.linalg.norm(tcp - (pos + rot @ [0.0, 0.0, 0.1425])) < 1e-9


def test_gripper_command_opens_and_closes_the_fingers(env):
    env.reset(seed=0)
    for command in (0.04, 0.01):
        action = env.home_command.copy()
        action[7] = command
        for _ in range(20):
            obs, *_ = env.step(action.astype(np.float32))
        assert obs["agent_pos"][7] == pytest.approx(command, abs=1e-3)


def test_tactile_noise_is_seeded_by_the_env():
    def first_image(seed: int) -> np.ndarray:
        env = compose(
            TactoGraspTask(), "sawyer", "pybullet", cameras=("tactile_left",), renderer="tiny"
        )
        try:
            return env.reset(seed=seed)[0]["pixels"]["tactile_left"]
        finally:
            env.close()

    a, b, c = first_image(1), first_image(1), first_image(2)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)
    assert 5.0 < float(a.astype(float).std()) < 9.0  # sigma 7 noise on the untouched gel


def test_options_are_checked_and_named():
    with pytest.raises(ValueError, match=r"renderer must be one of"):
        GRASP.make(renderer="opengl")
    with pytest.raises(TypeError, match=r"pybullet envs take no option frame_skip.*tactile_size"):
        GRASP.make(frame_skip=4)
    with pytest.raises(ValueError, match="PyBullet builds robots"):
        compose(TactoGraspTask(), "ur5e", "pybullet")
