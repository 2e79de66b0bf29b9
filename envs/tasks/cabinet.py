"""RMB's MujocoUR5eCabinet: a two-compartment cabinet with a hinged lid and a sliding door.

Geometry follows RMB's ``objects/cabinet/cabinet_body.xml`` (20 x 30 cm footprint, cabinet
frame x pointing away from the robot): the lower compartment (16 cm) is closed by a fixed panel
and a 15 x 15 cm sliding door (joint ``slide``, along +y, range 0..0.15 m) with a vertical tab
handle near its -y edge; the upper compartment (12 cm) has a lid hinged along its back top edge
(joint ``hinge``, about +y, range 0..pi, the front edge rising for positive angles) and a
10 x 4 cm notch in the top of its front wall, under the lid, where a finger gets under it.
The tab stands out further and is thicker than RMB's (4 x 1 cm instead of 1.5 x 0.6 cm) so
the Robotiq 2F-85's closed fingers can hook it with a margin. RMB's single env counts either
joint; here each is its own task: :class:`CabinetHingeTask` (lid opened beyond 120 degrees)
and :class:`CabinetSlideTask` (door slid beyond 0.12 m). The cabinet moves in y from -0.06 to
+0.09 m across the six worlds, as in RMB.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, ClassVar

import numpy as np

from rmb_lerobot.envs.tasks.base import StartPoses, Task
from rmb_lerobot.envs.workspace import RMB_TABLE, Workspace

if TYPE_CHECKING:
    from rmb_lerobot.envs.scene import SceneState

CABINET = "cabinet"  # the static body
LID = "cabinet_lid"
SLIDE_DOOR = "cabinet_slide_door"
HINGE = "hinge"
SLIDE = "slide"
HANDLE = "cabinet_handle"
# Cabinet-frame geometry (m) the experts use.
HALF_DEPTH = 0.1  # front faces at x = -HALF_DEPTH
HINGE_POS = np.array([0.095, 0.0, 0.28])  # lid hinge axis (along y)
LID_THICKNESS = 0.01
NOTCH_HALF_WIDTH = 0.05
NOTCH_Z = (0.24, 0.28)
SLIDE_POS = np.array([-0.095, 0.0, 0.0])  # slide-door body origin
SLIDE_RANGE = (0.0, 0.15)
DOOR_HALF_THICKNESS = 0.005
HANDLE_DEPTH = 0.04  # how far the tab stands out of the door's front face
HANDLE_HALF_THICKNESS = 0.005
HANDLE_HALF_HEIGHT = 0.03
HANDLE_POS = np.array([-DOOR_HALF_THICKNESS - HANDLE_DEPTH / 2, -0.135, 0.085])  # slide frame


class CabinetTask(Task):
    """The cabinet scene shared by both variants; subclasses say which joint must open."""

    world_offsets = np.array([[0.0, y, 0.0] for y in (-0.06, -0.03, 0.0, 0.03, 0.06, 0.09)])
    max_episode_steps = 400
    # RMB's MujocoUR5eCabinetEnv start pose.
    start_poses: ClassVar[StartPoses] = {
        "ur5e": ((np.pi, -0.4 * np.pi, -0.65 * np.pi, -0.2 * np.pi, np.pi / 2, np.pi / 2),)
    }

    def __init__(self, workspace: Workspace = RMB_TABLE) -> None:
        super().__init__(workspace)
        self.cabinet_nominal_pos = workspace.table.on_top(0.12, -0.05)


class CabinetHingeTask(CabinetTask):
    """Open the lid beyond 120 degrees (RMB's ``target_task="hinge"``)."""

    name = "cabinet_hinge"
    description = "Lift the cabinet's lid and flip it open."
    open_angle_deg = 120.0

    def is_success(self, scene: SceneState) -> bool:
        return bool(scene.joint_position(HINGE)[0] > np.deg2rad(self.open_angle_deg))


class CabinetSlideTask(CabinetTask):
    """Slide the door open beyond 0.12 m (RMB's ``target_task="slide"``)."""

    name = "cabinet_slide"
    description = "Hook the gripper onto the handle and slide the cabinet door open."
    open_distance = 0.12

    def is_success(self, scene: SceneState) -> bool:
        return bool(scene.joint_position(SLIDE)[0] > self.open_distance)
