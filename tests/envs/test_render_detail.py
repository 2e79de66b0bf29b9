"""Simplified visual meshes: same physics, nearly the same images, cheap env construction.

Image thresholds, at 320x240 for RMB's four cameras: simplification with the default 0.5 mm
bound changes the mean RGB value by at most 0.45 of 255 (hand camera; 0.2-0.3 elsewhere) and
moves less than 0.4 % of the depth pixels by over 1 cm (silhouette pixels). For scale, turning
the shoulder pan joint by just 0.5 degrees changes the full-detail images by up to 1.9 (RGB) and
1.9 % (depth). The tests allow 1.0 and 1 %: clearly below what half a degree of arm motion does,
with margin for rasteriser differences between Mesa versions.
"""

from __future__ import annotations

import time

import mujoco
import numpy as np
import pytest

from rmb_lerobot.envs.base import RmbEnv
from rmb_lerobot.envs.mujoco import meshes
from rmb_lerobot.envs.mujoco.render import MultiCameraRenderer
from rmb_lerobot.envs.mujoco.robots import build_ur5e
from rmb_lerobot.envs.mujoco.scene import build_scene
from rmb_lerobot.envs.registry import compose
from rmb_lerobot.envs.robots import UR5E
from rmb_lerobot.envs.tasks.insert import InsertTask
from rmb_lerobot.envs.workspace import RMB_TABLE

CAMERAS = ("front", "left", "right", "hand")
MAX_MEAN_RGB_DIFF = 1.0  # grey levels of 255
MAX_DEPTH_OUTLIERS = 0.01  # share of pixels whose depth moves by more than 1 cm


def _visual_faces(model: mujoco.MjModel) -> int:
    """Triangles the default cameras draw for mesh geoms (groups 0-2, non-colliding)."""
    return sum(
        int(model.mesh_facenum[model.geom_dataid[g]])
        for g in range(model.ngeom)
        if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH
        and model.geom_contype[g] == 0
        and model.geom_conaffinity[g] == 0
        and model.geom_group[g] < 3
    )


def _actions(env: RmbEnv, steps: int) -> list[np.ndarray]:
    rng = np.random.default_rng(7)
    out = []
    for i in range(steps):
        action = env.home_command.copy()
        action[:-1] += rng.normal(0.0, 0.08, 6)
        action[-1] = 255.0 if i >= steps // 2 else 0.0  # close the gripper half-way
        out.append(action)
    return out


@pytest.fixture(scope="module")
def physics_pair():
    full = compose(InsertTask(), cameras=(), render_mode=None, visual_mesh_error=0.0)
    light = compose(InsertTask(), cameras=(), render_mode=None)
    yield full, light
    full.close()
    light.close()


def test_simplified_meshes_are_much_lighter(physics_pair):
    full, light = physics_pair
    assert _visual_faces(light.sim.model) < 0.15 * _visual_faces(full.sim.model)
    assert light.sim.model.nmesh > full.sim.model.nmesh  # visual copies of shared gripper meshes


def test_collision_geometry_and_inertia_are_unchanged(physics_pair):
    full, light = physics_pair
    a, b = full.sim.model, light.sim.model
    for size in ("nbody", "ngeom", "njnt", "nq", "nv", "nu", "neq", "nsensordata"):
        assert getattr(a, size) == getattr(b, size), size
    for field in ("body_mass", "body_inertia", "body_ipos", "body_iquat", "body_pos", "body_quat"):
        np.testing.assert_array_equal(getattr(a, field), getattr(b, field), err_msg=field)
    colliding = np.flatnonzero((a.geom_contype != 0) | (a.geom_conaffinity != 0))
    assert len(colliding) > 0
    geom_fields = ("geom_type", "geom_size", "geom_pos", "geom_quat", "geom_dataid")
    for field in (*geom_fields, "geom_friction", "geom_solref", "geom_solimp", "geom_margin"):
        np.testing.assert_array_equal(
            getattr(a, field)[colliding], getattr(b, field)[colliding], err_msg=field
        )
    for g in colliding[a.geom_type[colliding] == mujoco.mjtGeom.mjGEOM_MESH]:
        mesh = a.geom_dataid[g]
        assert a.mesh(mesh).name == b.mesh(mesh).name
        va, vb = a.mesh_vertadr[mesh], b.mesh_vertadr[mesh]
        n = a.mesh_vertnum[mesh]
        assert n == b.mesh_vertnum[mesh]
        np.testing.assert_array_equal(a.mesh_vert[va : va + n], b.mesh_vert[vb : vb + n])


def test_physics_is_identical_with_and_without_simplification(physics_pair):
    full, light = physics_pair
    trajectories = []
    for env in (full, light):
        env.reset(seed=3, options={"world_idx": 2})
        qpos, sensors = [], []
        for action in _actions(env, 40):
            env.step(action)
            qpos.append(env.sim.data.qpos.copy())
            sensors.append(env.sim.data.sensordata.copy())
        trajectories.append((np.array(qpos), np.array(sensors)))
    np.testing.assert_array_equal(trajectories[0][0], trajectories[1][0])
    np.testing.assert_array_equal(trajectories[0][1], trajectories[1][1])
    assert np.ptp(trajectories[0][0], axis=0).max() > 0.05  # the arm did move


def test_images_stay_close_to_full_detail():
    envs = [
        compose(
            InsertTask(),
            cameras=CAMERAS,
            image_size=(320, 240),
            depth=True,
            render_mode=None,
            visual_mesh_error=error,
        )
        for error in (0.0, meshes.DEFAULT_VISUAL_MESH_ERROR)
    ]
    try:
        frames = []
        for env in envs:
            obs, _ = env.reset(seed=0, options={"world_idx": 0})
            seq = [(obs["pixels"], env.rmb_step_data())]
            for action in _actions(env, 10):
                obs, *_ = env.step(action)
            seq.append((obs["pixels"], env.rmb_step_data()))
            frames.append(seq)
        for (rgb_full, step_full), (rgb_light, step_light) in zip(*frames, strict=True):
            for cam in CAMERAS:
                diff = np.abs(rgb_full[cam].astype(np.float64) - rgb_light[cam]).mean()
                assert diff < MAX_MEAN_RGB_DIFF, (cam, diff)
                depth_full = step_full[f"{cam}_depth_image"]
                depth_light = step_light[f"{cam}_depth_image"]
                moved = np.abs(depth_full - depth_light) > 0.01
                assert moved.mean() < MAX_DEPTH_OUTLIERS, (cam, moved.mean())
                assert np.median(np.abs(depth_full - depth_light)) < 1e-4
    finally:
        for env in envs:
            env.close()


def test_renderer_without_antialiasing(camera_env):
    camera_env.reset(seed=0)
    samples = camera_env.sim.model.vis.quality.offsamples
    plain = MultiCameraRenderer(camera_env.sim.model, 64, 48, antialias=False)
    try:
        rgb, depth = plain.render(camera_env.sim.data, ["front"], depth=True)
    finally:
        plain.close()
    assert camera_env.sim.model.vis.quality.offsamples == samples == 4
    smooth_rgb, smooth_depth = camera_env.sim._get_renderer().render(
        camera_env.sim.data, ["front"], depth=True
    )
    assert rgb["front"].shape == (48, 64, 3) and rgb["front"].std() > 5
    # Only edge pixels differ (here 64x48, where edges are a large share of the image).
    assert np.abs(rgb["front"].astype(np.float64) - smooth_rgb["front"]).mean() < 5.0
    assert np.median(np.abs(depth["front"] - smooth_depth["front"])) < 0.01


def test_cache_miss_then_hit(tmp_path, monkeypatch):
    monkeypatch.setenv("RMB_LEROBOT_CACHE", str(tmp_path))
    monkeypatch.setattr(meshes, "_memory_cache", {})
    start = time.perf_counter()
    first = build_scene(build_ur5e(UR5E), RMB_TABLE).compile()
    miss = time.perf_counter() - start
    cached = sorted(p.name for p in (tmp_path / "visual_meshes").iterdir())
    assert len(cached) == 2 and all(name.endswith(".npz") for name in cached)  # arm, gripper

    def no_recompute(*args, **kwargs):
        raise AssertionError("cache hit expected")

    monkeypatch.setattr(meshes, "_memory_cache", {})
    monkeypatch.setattr(meshes, "compute_simplified_meshes", no_recompute)
    start = time.perf_counter()
    second = build_scene(build_ur5e(UR5E), RMB_TABLE).compile()
    hit = time.perf_counter() - start
    np.testing.assert_array_equal(first.mesh_vert, second.mesh_vert)
    np.testing.assert_array_equal(first.mesh_face, second.mesh_face)
    # Generous bounds for a shared 2-core machine (measured: ~2.5 s miss, ~0.3 s hit).
    assert miss < 30.0 and hit < 5.0, (miss, hit)


def test_unwritable_cache_still_builds(tmp_path, monkeypatch):
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    monkeypatch.setenv("RMB_LEROBOT_CACHE", str(blocker))
    monkeypatch.setattr(meshes, "_memory_cache", {})
    model = build_scene(build_ur5e(UR5E), RMB_TABLE).compile()
    assert _visual_faces(model) < 30_000


def test_full_detail_leaves_the_spec_untouched():
    spec = build_scene(build_ur5e(UR5E, visual_mesh_error=0.0), RMB_TABLE)
    assert all(mesh.file for mesh in spec.meshes)
    assert not any(mesh.name.endswith(meshes.VISUAL_SUFFIX) for mesh in spec.meshes)
    with pytest.raises(ValueError, match="visual_mesh_error"):
        build_ur5e(UR5E, visual_mesh_error=-1.0)


def test_simplify_mesh_keeps_the_surface_within_the_bound():
    # A finely tessellated unit-radius sphere (in mm-sized units: radius 0.05 m).
    radius, n = 0.05, 64
    theta, phi = np.meshgrid(np.linspace(0, np.pi, n), np.linspace(0, 2 * np.pi, 2 * n))
    grid = radius * np.stack(
        [np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1
    )
    idx = np.arange(grid.shape[0] * grid.shape[1]).reshape(grid.shape[:2])
    quads = np.stack([idx[:-1, :-1], idx[1:, :-1], idx[1:, 1:], idx[:-1, 1:]], -1).reshape(-1, 4)
    faces = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    vertices = grid.reshape(-1, 3)
    # Duplicated vertices (pole rows, the seam) are welded; degenerate triangles dropped.
    welded_vertices, welded_faces = meshes.weld(vertices, faces)
    assert len(welded_vertices) < len(vertices)
    error = 5e-4
    new_vertices, new_faces = meshes.simplify_mesh(vertices, faces, error)
    assert 50 < len(new_faces) < 0.3 * len(welded_faces)
    # Vertices are a subset of the originals: all on the sphere.
    np.testing.assert_allclose(np.linalg.norm(new_vertices, axis=1), radius, rtol=1e-6)
    # Triangle centres sag inside the sphere by about the error bound, not much more.
    centres = new_vertices[new_faces].mean(axis=1)
    assert (radius - np.linalg.norm(centres, axis=1)).max() < 3 * error
