"""The shared world of RMB's MuJoCo UR5e tasks, built with :class:`mujoco.MjSpec`.

Floor, table, the robot's stand, lights and the fixed cameras ``front``, ``left``, ``right``
(the robot adds ``hand``). Dimensions follow RMB's ``env_ur5e_*.xml``: table top at
z = 0.815 m centred on the origin, robot base at (-0.605, 0, 0.8), timestep 0.004 s, and
``statistic.extent = 2`` (so depth near/far planes are 0.02 m / 100 m as in RMB).
Tasks add their props to the returned spec before it is compiled.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
from rmb_lerobot.envs.mujoco.meshes import DEFAULT_VISUAL_MESH_ERROR
from rmb_lerobot.envs.mujoco.robot import RobotSpec, build_robot_spec

TIMESTEP = 0.004
TABLE_HALF_SIZE = (0.275, 0.5)
TABLE_TOP_Z = 0.815


@dataclass(frozen=True)
class SceneCamera:
    """A fixed camera placed by position and the point it looks at (world z is up)."""

    name: str
    pos: tuple[float, float, float]
    lookat: tuple[float, float, float]
    fovy: float = 45.0

    def quat(self) -> np.ndarray:
        """Camera orientation: MuJoCo cameras look along -z with +y up in the image."""
        forward = np.subtract(self.lookat, self.pos).astype(np.float64)
        forward /= np.linalg.norm(forward)
        right = np.cross(forward, [0.0, 0.0, 1.0])
        if np.linalg.norm(right) < 1e-9:
            raise ValueError(f"camera {self.name!r} looks straight up or down; give it a tilt")
        right /= np.linalg.norm(right)
        up = np.cross(right, forward)
        mat = np.column_stack([right, up, -forward])
        quat = np.empty(4)
        mujoco.mju_mat2Quat(quat, mat.reshape(9))
        return quat


# RMB's front camera (pos 0.5 0 1.5, pitched 45 deg down towards the robot) and two side views.
SCENE_CAMERAS = (
    SceneCamera("front", pos=(0.5, 0.0, 1.5), lookat=(-0.185, 0.0, 0.815)),
    SceneCamera("left", pos=(0.0, 0.75, 1.3), lookat=(-0.15, 0.0, 0.9)),
    SceneCamera("right", pos=(0.0, -0.75, 1.3), lookat=(-0.15, 0.0, 0.9)),
)


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


def build_scene(
    robot: RobotSpec,
    *,
    max_render_size: tuple[int, int] = (640, 480),
    visual_mesh_error: float = DEFAULT_VISUAL_MESH_ERROR,
) -> mujoco.MjSpec:
    """World + robot, ready for a task to add props. ``max_render_size`` (W, H) sizes the
    offscreen framebuffer, which must be at least as large as any rendered image;
    ``visual_mesh_error`` (m) bounds the robot's visual mesh simplification (0: original)."""
    spec = build_robot_spec(robot, visual_mesh_error=visual_mesh_error)
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
    hx, hy = TABLE_HALF_SIZE
    table = world.add_body(name="table")
    table.add_geom(
        type=mujoco.mjtGeom.mjGEOM_BOX, size=[hx, hy, 0.4], pos=[0, 0, 0.4], material="table_base"
    )
    table.add_geom(
        name="table_top",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[hx, hy, 0.0075],
        pos=[0, 0, TABLE_TOP_Z - 0.0075],
        material="table_top",
    )
    stand = world.add_body(name="stand")
    stand.add_geom(
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[0.33, 0.33, 0.4],
        pos=[robot.mount_pos[0], robot.mount_pos[1], 0.4],
        material="stand",
    )
    for cam in SCENE_CAMERAS:
        world.add_camera(name=cam.name, pos=list(cam.pos), quat=list(cam.quat()), fovy=cam.fovy)
    return spec
