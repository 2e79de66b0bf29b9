"""The world pose of each fixed camera, recorded next to its fovy when depth is recorded.

``<camera>_depth_image_pose`` (:func:`rmb_lerobot.keys.camera_pose_attr`) is the 4x4
world-from-camera transform in OpenCV camera axes, so back-projected depth lands in the world.
"""

from __future__ import annotations

import gymnasium as gym
import mujoco
import numpy as np
import pytest

from rmb_lerobot import RmbFormatError, find_episodes, open_episode
from rmb_lerobot import keys as K
from rmb_lerobot.cli.collect import main
from rmb_lerobot.converters.attrs import checked_attrs
from rmb_lerobot.envs.registry import ENVS
from rmb_lerobot.envs.workspace import RMB_TABLE
from rmb_lerobot.pointcloud import depth_to_points, opencv_camera_pose, transform_points


def make(task: str, size: int, cameras=("front",), depth: bool = True):
    return gym.make(ENVS[task].gym_id, cameras=cameras, image_size=(size, size), depth=depth)


def test_recorded_pose_is_mujocos_camera_pose_in_opencv_axes():
    env = make("insert", 32, cameras=("front", "left", "hand"))
    try:
        core = env.unwrapped
        env.reset(seed=0, options={"world_idx": 0})
        attrs = core.rmb_attrs()
        data = core.sim.data
        for camera in ("front", "left"):
            pose = np.asarray(attrs[K.camera_pose_attr(camera)])
            view = data.camera(camera)
            assert pose.shape == (4, 4) and np.allclose(pose[3], [0, 0, 0, 1])
            np.testing.assert_allclose(pose, opencv_camera_pose(view.xpos, view.xmat))
            # MuJoCo looks along its camera's -z with y up: OpenCV z = -z, y = -y.
            rot = view.xmat.reshape(3, 3)
            np.testing.assert_allclose(pose[:3, 2], -rot[:, 2])
            np.testing.assert_allclose(pose[:3, 1], -rot[:, 1])
            np.testing.assert_allclose(pose[:3, 0], rot[:, 0])
        # The workspace record: front at (0.5, 0, 1.5) looking at (-0.185, 0, 0.815).
        front = np.asarray(attrs[K.camera_pose_attr("front")])
        spec = next(c for c in RMB_TABLE.cameras if c.name == "front")
        forward = np.subtract(spec.lookat, spec.pos)
        np.testing.assert_allclose(front[:3, 3], spec.pos, atol=1e-9)
        np.testing.assert_allclose(front[:3, 2], forward / np.linalg.norm(forward), atol=1e-9)
        assert front[2, 1] < 0  # image "down" points down in the world
        # The hand camera moves with the arm: no single pose, so none is recorded.
        assert K.camera_pose_attr("hand") not in attrs
        assert core.sim.camera_pose("hand") is None
    finally:
        env.close()


def test_no_pose_without_depth():
    env = make("insert", 32, depth=False)
    try:
        env.reset(seed=0)
        attrs = env.unwrapped.rmb_attrs()
        assert K.fovy_attr("front") in attrs and K.camera_pose_attr("front") not in attrs
    finally:
        env.close()


def test_reading_the_pose_changes_no_step():
    """Two runs on this machine, one asking for the attributes every step: same observations."""
    runs = []
    for ask in (False, True):
        env = make("insert", 16)
        try:
            core = env.unwrapped
            obs, _ = env.reset(seed=3, options={"world_idx": 2})
            action = core.command.copy()
            frames = []
            for _ in range(5):
                if ask:
                    core.rmb_attrs()
                obs, *_ = env.step(action)
                frames.append((obs["agent_pos"].copy(), obs["depth"]["front"].copy()))
            runs.append(frames)
        finally:
            env.close()
    for (state_a, depth_a), (state_b, depth_b) in zip(*runs, strict=True):
        np.testing.assert_array_equal(state_a, state_b)
        np.testing.assert_array_equal(depth_a, depth_b)


@pytest.mark.parametrize("task", ["insert", "pick", "cloth"])
def test_table_top_pixels_back_project_to_the_table_height(task):
    """Physical check of fovy + pose: the pixels MuJoCo says show the table top land on its
    surface, z = 0.815 m, in every world. 128x128: RMB's principal point (W/2, H/2 on pixel
    indices, not centres) puts them ~3 mm high there (~6 mm at 64x64, ~1.5 mm at 256x256)."""
    env = make(task, 128)
    try:
        core = env.unwrapped
        seg = mujoco.Renderer(core.sim.model, 128, 128)
        seg.enable_segmentation_rendering()
        table_top = core.sim.model.geom("table_top").id
        poses = []
        for world in (0, 2, 5):
            obs, _ = env.reset(seed=world, options={"world_idx": world})
            attrs = core.rmb_attrs()
            pose = np.asarray(attrs[K.camera_pose_attr("front")])
            poses.append(pose)
            seg.update_scene(core.sim.data, camera="front")
            on_top = seg.render()[..., 0] == table_top  # geom ids, -1 for none
            depth = (obs["depth"]["front"] / 1000.0).astype(np.float32)
            points, _ = depth_to_points(depth, attrs[K.fovy_attr("front")])
            world_z = transform_points(points, matrix=pose)[:, 2]
            z = world_z[on_top[depth > 0]]
            assert len(z) > 2000
            assert abs(np.median(z) - RMB_TABLE.table.top_z) < 0.004
            assert np.mean(np.abs(z - RMB_TABLE.table.top_z) < 0.005) > 0.98  # edges blend
        seg.close()
        for pose in poses[1:]:  # the cameras are the workspace's: the same in every world
            np.testing.assert_allclose(pose, poses[0])
    finally:
        env.close()


def test_collect_writes_the_pose_of_fixed_depth_cameras(tmp_path, capsys):
    out = tmp_path / "demos"
    args = ["MujocoUR5eInsert", "--episodes", "1", "--out", str(out), "--world-idx", "3"]
    code = main([*args, "--cameras", "front", "hand", "--image-size", "32", "24"])
    assert code == 0, capsys.readouterr().err
    with open_episode(find_episodes(out)[0]) as ep:
        pose = np.asarray(ep.attrs[K.camera_pose_attr("front")])
        assert pose.shape == (4, 4) and pose.dtype == np.float64
        np.testing.assert_allclose(pose[:3, 3], (0.5, 0.0, 1.5))
        assert K.camera_pose_attr("hand") not in ep.attrs


def test_conversion_checks_the_pose_attribute():
    """rmb-convert copies it into meta/rmb.json as nested lists, or stops naming it."""
    pose = np.eye(4)
    pose[:3, 3] = (0.5, 0.0, 1.5)
    name = K.camera_pose_attr("front")
    assert checked_attrs({name: pose}, "ep.rmb")[name] == pose.tolist()
    for bad in (np.eye(3), np.full((4, 4), np.nan), np.ones((4, 4)), "front"):
        with pytest.raises(RmbFormatError, match=r"front_depth_image_pose.*4x4 world-from-camera"):
            checked_attrs({name: bad}, "ep.rmb")
