"""The world of RMB's MuJoCo tasks, built with :class:`mujoco.MjSpec` from records.

The robot model (its builder's spec, :mod:`rmb_lerobot.envs.mujoco.robots`) plus floor, lights,
the robot's stand and the workspace's table and fixed cameras
(:mod:`rmb_lerobot.envs.workspace`; RMB's UR5e scene: table top at z = 0.815 m centred on the
origin, cameras ``front``, ``left``, ``right``; the robot adds ``hand``). Timestep 0.004 s,
``statistic.extent = 2`` (so depth near/far planes are 0.02 m / 100 m as in RMB). Tasks add
their props to the returned spec before it is compiled.
"""

from __future__ import annotations

import mujoco
import numpy as np

from rmb_lerobot.envs.mujoco.models.common import RobotModel
from rmb_lerobot.envs.workspace import TABLE_TOP_THICKNESS, SceneCamera, Workspace

TIMESTEP = 0.004


def camera_quat(camera: SceneCamera) -> np.ndarray:
    """Camera orientation: MuJoCo cameras look along -z with +y up in the image."""
    forward = np.subtract(camera.lookat, camera.pos).astype(np.float64)
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    if np.linalg.norm(right) < 1e-9:
        raise ValueError(f"camera {camera.name!r} looks straight up or down; give it a tilt")
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    mat = np.column_stack([right, up, -forward])
    quat = np.empty(4)
    mujoco.mju_mat2Quat(quat, mat.reshape(9))
    return quat


def _add_materials(spec: mujoco.MjSpec) -> None:
    spec.add_texture(
        name="skybox",
        type=mujoco.mjtTexture.mjTEXTURE_SKYBOX,
        builtin=mujoco.mjtBuiltin.mjBUILTIN_GRADIENT,
        rgb1=[0.9, 1.0, 1.0],
        rgb2=[0.9, 1.0, 1.0],
        width=64,
        height=384,
    )
    spec.add_texture(
        name="floor",
        type=mujoco.mjtTexture.mjTEXTURE_2D,
        builtin=mujoco.mjtBuiltin.mjBUILTIN_CHECKER,
        rgb1=[0.35, 0.37, 0.4],
        rgb2=[0.3, 0.32, 0.35],
        width=256,
        height=256,
    )
    floor = spec.add_material(name="floor", texrepeat=[4, 4], specular=0.2, shininess=0.3)
    floor.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = "floor"
    spec.add_material(name="table_base", rgba=[0.8, 0.75, 0.6, 1.0], specular=0.3)
    spec.add_material(name="table_top", rgba=[0.9, 0.88, 0.82, 1.0], specular=0.0)
    spec.add_material(name="stand", rgba=[0.05, 0.22, 0.48, 1.0], specular=0.3)


def _add_table(world: mujoco.MjsBody, workspace: Workspace) -> None:
    """The workspace's table: a base box from the floor and the board on it."""
    table = workspace.table
    hx, hy = table.half_size
    cx, cy, top = table.top_centre
    body = world.add_body(name="table", pos=[cx, cy, 0.0])
    base = table.base_half_z
    body.add_geom(
        type=mujoco.mjtGeom.mjGEOM_BOX, size=[hx, hy, base], pos=[0, 0, base], material="table_base"
    )
    board = TABLE_TOP_THICKNESS / 2
    body.add_geom(
        name="table_top",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[hx, hy, board],
        pos=[0, 0, top - board],
        material="table_top",
    )


def build_scene(
    robot: RobotModel, workspace: Workspace, *, max_render_size: tuple[int, int] = (640, 480)
) -> mujoco.MjSpec:
    """World + robot, ready for a task to add props: the robot model's spec with the
    workspace's table and fixed cameras, the robot's stand, floor and lights added.
    ``max_render_size`` (W, H) sizes the offscreen framebuffer, which must be at least as large
    as any rendered image."""
    spec = robot.spec
    spec.modelname = f"rmb_{robot.name}"
    spec.compiler.autolimits = True
    spec.option.timestep = TIMESTEP
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.stat.extent = 2.0
    spec.stat.center = [0.0, 0.0, 0.8]
    spec.visual.global_.offwidth = max(int(max_render_size[0]), 640)
    spec.visual.global_.offheight = max(int(max_render_size[1]), 480)
    spec.visual.headlight.diffuse = [0.6, 0.6, 0.6]
    spec.visual.headlight.ambient = [0.1, 0.1, 0.1]
    spec.visual.headlight.specular = [0.0, 0.0, 0.0]
    _add_materials(spec)

    world = spec.worldbody
    world.add_light(
        name="top",
        pos=[0, 0, 1.5],
        dir=[0, 0, -1],
        diffuse=[0.5, 0.5, 0.5],
        castshadow=False,
        type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL,
    )
    world.add_geom(
        name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 0.05], material="floor"
    )
    table = workspace.table
    if table.top_z > 0:  # a workspace whose "table top" is the floor (z = 0) has no table
        _add_table(world, workspace)
    if robot.stand is not None:
        stand = world.add_body(name="stand")
        stand.add_geom(
            type=mujoco.mjtGeom.mjGEOM_BOX,
            size=list(robot.stand.half_size),
            pos=list(robot.stand.pos),
            material="stand",
        )
    for cam in workspace.cameras:
        world.add_camera(
            name=cam.name, pos=list(cam.pos), quat=list(camera_quat(cam)), fovy=cam.fovy
        )
    return spec
