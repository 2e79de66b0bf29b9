"""LeRobot device plugins for the real arms: robots ``rmb_ur5e``, ``rmb_xarm7``,
``rmb_ur5e_dual`` and the teleoperators ``rmb_scripted`` (a joint-space script) and
``rmb_keyboard`` (RMB's keys as end-effector velocities, headless).

Importing this package registers the five types (:mod:`.config`). The device classes are
exported here on purpose: LeRobot looks a plugin's device class up in the *parent* package of
its config's module (``lerobot.utils.import_utils.make_device_from_device_class``), never in
the config's module itself. Building a device imports the drivers; nothing here imports an SDK
or MuJoCo.
"""

from rmb_lerobot.envs.real.lerobot_devices.config import (
    RmbArmConfig,
    RmbKeyboardConfig,
    RmbScriptedConfig,
    RmbUR5eConfig,
    RmbUR5eDualConfig,
    RmbXarm7Config,
)
from rmb_lerobot.envs.real.lerobot_devices.robots import RmbArmRobot, RmbUR5e, RmbUR5eDual, RmbXarm7
from rmb_lerobot.envs.real.lerobot_devices.teleop import RmbScripted
from rmb_lerobot.envs.real.lerobot_devices.teleop_keyboard import RmbKeyboard

__all__ = [
    "RmbArmConfig",
    "RmbArmRobot",
    "RmbKeyboard",
    "RmbKeyboardConfig",
    "RmbScripted",
    "RmbScriptedConfig",
    "RmbUR5e",
    "RmbUR5eConfig",
    "RmbUR5eDual",
    "RmbUR5eDualConfig",
    "RmbXarm7",
    "RmbXarm7Config",
]
