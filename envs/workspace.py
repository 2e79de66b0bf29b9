"""The arena a task is placed in: the table and the fixed cameras, simulator-neutral.

Tasks place their objects relative to :attr:`Workspace.table` (its top surface height and
centre) instead of module constants, so one task serves every robot whose scene has such a
table; the robots' own mounts come from their records (:mod:`rmb_lerobot.envs.robots`). A
backend builds the workspace in its simulator (:func:`rmb_lerobot.envs.mujoco.scene.build_scene`
for MuJoCo).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

TABLE_TOP_THICKNESS = 0.015  # m, RMB's table board


@dataclass(frozen=True)
class Table:
    """A table: the centre of its top surface (world frame) and its half size in x and y.

    It is drawn as a board (:data:`TABLE_TOP_THICKNESS`) on a base box from the floor;
    ``base_half_height`` is the base's half height (None: up to the board).
    """

    top_centre: tuple[float, float, float]
    half_size: tuple[float, float]
    base_half_height: float | None = None

    @property
    def base_half_z(self) -> float:
        if self.base_half_height is not None:
            return self.base_half_height
        return (self.top_z - TABLE_TOP_THICKNESS) / 2

    @property
    def top_z(self) -> float:
        """Height of the table's top surface (m)."""
        return self.top_centre[2]

    def on_top(self, x: float, y: float, height: float = 0.0) -> np.ndarray:
        """World position ``(x, y)`` at ``height`` above the table top (x, y in the world)."""
        return np.array([x, y, self.top_z + height])


@dataclass(frozen=True)
class SceneCamera:
    """A fixed camera placed by position and the point it looks at (world z is up)."""

    name: str
    pos: tuple[float, float, float]
    lookat: tuple[float, float, float]
    fovy: float = 45.0


@dataclass(frozen=True)
class Workspace:
    """Table and fixed cameras of a scene (the robot adds its hand cameras)."""

    name: str
    table: Table
    cameras: tuple[SceneCamera, ...]

    @property
    def camera_names(self) -> tuple[str, ...]:
        return tuple(camera.name for camera in self.cameras)


RMB_TABLE = Workspace(
    name="table",
    # RMB's env_ur5e_*.xml: table top at z = 0.815 m centred on the origin.
    table=Table(top_centre=(0.0, 0.0, 0.815), half_size=(0.275, 0.5), base_half_height=0.4),
    # RMB's front camera (pos 0.5 0 1.5, pitched 45 deg down towards the robot), two side views.
    cameras=(
        SceneCamera("front", pos=(0.5, 0.0, 1.5), lookat=(-0.185, 0.0, 0.815)),
        SceneCamera("left", pos=(0.0, 0.75, 1.3), lookat=(-0.15, 0.0, 0.9)),
        SceneCamera("right", pos=(0.0, -0.75, 1.3), lookat=(-0.15, 0.0, 0.9)),
    ),
)
"""The table scene of RMB's MuJoCo UR5e tasks."""

# RMB's cameras of its other MuJoCo scenes, given as MJCF euler angles there; here as the point
# on the camera's axis at the table-top height (same pose: no roll in any of them).
XARM_TABLE = Workspace(
    name="xarm_table",
    # env_xarm7_*.xml lines 29-34: a 0.6 x 0.9 m table top at z = 0.74 m (0.721 + 0.019).
    table=Table(top_centre=(0.0, 0.0, 0.74), half_size=(0.3, 0.45)),
    cameras=(
        SceneCamera("front", pos=(0.65, 0.0, 1.5), lookat=(-0.11, 0.0, 0.74)),  # 45 deg down
        SceneCamera("left", pos=(0.0, -0.75, 1.35), lookat=(0.0, -0.14, 0.74)),  # 45 deg, +y
        SceneCamera("right", pos=(0.0, 0.75, 1.35), lookat=(0.0, 0.14, 0.74)),  # 45 deg, -y
    ),
)
"""The table scene of RMB's MuJoCo xArm7 tasks (the arm stands on the table)."""

DUAL_TABLE = Workspace(
    name="dual_table",
    table=RMB_TABLE.table,
    # env_ur5e_dual_cable.xml lines 17-20: front as the single UR5e's, left/right 45 deg down
    # from the sides, and ``rear`` behind the robots looking over them (22 deg down, +x).
    cameras=(
        RMB_TABLE.cameras[0],
        SceneCamera("left", pos=(0.0, -0.75, 1.35), lookat=(0.0, -0.215, 0.815)),
        SceneCamera("right", pos=(0.0, 0.75, 1.35), lookat=(0.0, 0.215, 0.815)),
        SceneCamera("rear", pos=(-0.9, 0.0, 1.35), lookat=(0.42, 0.0, 0.815)),
    ),
)
"""RMB's UR5e table seen by a dual-arm robot: the front/left/right views and a rear one."""

# RMB's TACTO scenes (PyBullet): objects on the floor in front of the Sawyer, no table. Their
# "front" camera orbits a target (TactoSawyerEnvBase.py:231-239: computeViewMatrixFromYawPitchRoll
# with yaw 90, pitch -30, fov 60); here as the position that view puts the camera at (distance
# along the view direction, checked against PyBullet's matrix in tests/envs/pybullet).
TACTO_FLOOR = Workspace(
    name="tacto_floor",
    table=Table(top_centre=(0.5, 0.0, 0.0), half_size=(1.0, 1.0)),
    cameras=(
        SceneCamera(
            "front",
            pos=(0.5 + 0.4 * np.cos(np.pi / 6), 0.0, 0.05 + 0.4 * 0.5),
            lookat=(0.5, 0.0, 0.05),
            fovy=60.0,
        ),
    ),
)
"""The floor of RMB's TactoSawyerGrasp and TactoSawyerInsert (front camera 0.4 m from (0.5, 0,
0.05))."""

TACTO_SPOON_FLOOR = Workspace(
    name="tacto_spoon_floor",
    table=TACTO_FLOOR.table,
    cameras=(
        SceneCamera(
            "front",
            pos=(0.8 + 1.0 * np.cos(np.pi / 6), 0.0, 0.05 + 1.0 * 0.5),
            lookat=(0.8, 0.0, 0.05),
            fovy=60.0,
        ),
    ),
)
"""The floor of RMB's TactoSawyerSpoon: its own front camera, 1 m from (0.8, 0, 0.05)."""

G1_TABLE = Workspace(
    name="g1_table",
    # env_g1_bottles.xml: the ALOHA table turned by -90 deg about z at (-0.45, 0), its
    # 1.22 x 0.74 m top at z = 0 with the floor at -0.75; here the floor is at 0. RMB's scene
    # has no fixed camera (it records the robot's ``head``); ``front`` here faces the robot
    # across the table (an overview for rendering and policies, 35 deg down).
    table=Table(top_centre=(-0.45, 0.0, 0.75), half_size=(0.37, 0.61)),
    cameras=(SceneCamera("front", pos=(0.25, 0.0, 1.45), lookat=(-0.75, 0.0, 0.75)),),
)
"""The table in front of RMB's Unitree G1 (the robot stands at x = -1.0 facing +x)."""

# RMB's ALOHA scenes (aloha_table_body.xml, inside a body turned -90 deg about z): the same
# 0.74 x 1.22 m table top at z = 0 over a floor at -0.75 (here the floor is at 0, so +0.75);
# ``overhead_cam`` 1.03 m above the top, 0.30 m behind the centre, pitched 25 deg from straight
# down; ``worms_eye_cam`` just above the top at the back edge, looking across it 5.4 deg up;
# both RealSense D405 (focal 1.93 mm, sensor 2.14 mm high: fovy 58.0 deg).
_D405_FOVY = float(np.degrees(2 * np.arctan(2.14 / 2 / 1.93)))
ALOHA_TABLE = Workspace(
    name="aloha_table",
    table=Table(top_centre=(0.0, 0.0, 0.75), half_size=(0.37, 0.61)),
    cameras=(
        SceneCamera("overhead_cam", (-0.3038, 0.0, 1.7752), (0.1741, 0.0, 0.75), _D405_FOVY),
        SceneCamera("worms_eye_cam", (-0.3772, 0.0, 0.7816), (0.6184, 0.0, 0.8759), _D405_FOVY),
    ),
)
"""The table of RMB's MuJoCo ALOHA tasks (both arms stand on it, facing each other)."""

HSR_FLOOR = Workspace(
    name="hsr_floor",
    # env_hsr_tidyup.xml: no table, the bottles and containers stand on the floor (the "table
    # top" is the floor, z = 0, and the MuJoCo scene draws no table). RMB's scene has no fixed
    # camera (it records the robot's ``head`` and ``hand``); ``front`` here looks at the robot
    # over the containers (an overview for rendering and policies, 40 deg down).
    table=Table(top_centre=(1.0, 0.0, 0.0), half_size=(1.0, 1.0)),
    cameras=(SceneCamera("front", pos=(2.1, 0.0, 1.3), lookat=(0.55, 0.0, 0.0)),),
)
"""The floor of RMB's MuJoCo HSR TidyUp (the robot starts at the origin facing +x)."""

WORKSPACES: dict[str, Workspace] = {
    ws.name: ws
    for ws in (
        RMB_TABLE,
        XARM_TABLE,
        DUAL_TABLE,
        TACTO_FLOOR,
        TACTO_SPOON_FLOOR,
        G1_TABLE,
        ALOHA_TABLE,
        HSR_FLOOR,
    )
}
