"""Make the input device ``rmb-teleop --input-device`` names, for an env's robot.

The keyboard and replay devices live beside this module; the SpaceMouse and GELLO devices
are imported only when asked for (their SDKs are optional extras), from
``rmb_lerobot.envs.teleop.spacemouse`` / ``.gello``. ``config`` is the device's YAML in RMB's
format (``--input_device_config``): for a SpaceMouse one ``/dev/hidrawN`` per arm (optional:
without it the first SpaceMouse found drives the first arm), for GELLO its servos per arm
(required). A device module that defines ``make_device(robot, config)`` is built by it.
"""

from __future__ import annotations

import importlib
from pathlib import Path

from rmb_lerobot import keys as K
from rmb_lerobot.envs.robots import Robot
from rmb_lerobot.envs.teleop.device import InputDevice
from rmb_lerobot.envs.teleop.keyboard import KeyboardDevice, gripper_step_for
from rmb_lerobot.envs.teleop.replay import ReplayDevice

INPUT_DEVICES = ("keyboard", "spacemouse", "gello", "replay")
_LAZY = {
    "spacemouse": "rmb_lerobot.envs.teleop.spacemouse",
    "gello": "rmb_lerobot.envs.teleop.gello",
}


def make_device(
    name: str,
    robot: Robot,
    *,
    config: Path | None = None,
    replay_log: Path | None = None,
    replay_key: str = K.COMMAND_JOINT_POS,
) -> InputDevice:
    """The input device ``name`` for ``robot`` (not yet connected).

    Args:
        name: One of :data:`INPUT_DEVICES`.
        robot: The robot it drives (arms, grippers).
        config: The device's configuration file (SpaceMouse, GELLO).
        replay_log: The episode to replay (``replay``).
        replay_key: The key to replay (``replay``).

    Returns:
        The device.

    Raises:
        ValueError: An unknown device, or ``replay`` without a log.
        ImportError: The device's module (or its ``make_device``) is not available.
    """
    if name == "keyboard":
        steps = [gripper_step_for(arm.gripper.command_range) for arm in robot.arms]
        # No robot record carries a mobile base yet; the keyboard's base keys wait for one.
        has_base = bool(getattr(robot, "base", None))
        return KeyboardDevice(num_arms=len(robot.arms), has_base=has_base, gripper_step=steps)
    if name == "replay":
        if replay_log is None:
            raise ValueError("--input-device replay needs --replay-log EPISODE")
        return ReplayDevice(replay_log, robot, replay_key)
    if name not in _LAZY:
        raise ValueError(f"unknown input device {name!r}; use one of {', '.join(INPUT_DEVICES)}")
    module = _import_device_module(name)
    factory = getattr(module, "make_device", None)
    if factory is not None:  # a module may build its device from the robot itself
        return factory(robot, config)
    if name == "spacemouse":
        paths = () if config is None else spacemouse_paths(config)
        return module.SpaceMouseDevice(module.SpaceMouseConfig(paths=paths))
    if config is None:
        raise ValueError(
            "--input-device gello needs --input-device-config: RMB's GELLO YAML (ports, joint "
            "ids, offsets, signs and gripper per arm, e.g. Gello_RealUR5eDual.yaml)"
        )
    return module.GelloDevice(module.load_rmb_gello_yaml(config))


def _import_device_module(name: str):
    module_name = _LAZY[name]
    try:
        return importlib.import_module(module_name)
    except ModuleNotFoundError as exc:
        if exc.name != module_name:
            raise  # the module exists but its own import failed: show that error
        raise ImportError(
            f"--input-device {name}: {module_name} is not part of this installation"
        ) from exc


def spacemouse_paths(config: Path) -> tuple[str, ...]:
    """The ``/dev/hidrawN`` per arm of RMB's SpaceMouse YAML (``SpaceMouseDual.yaml``:
    ``{0: {device_params: {path: /dev/hidraw3}}, 1: ...}``), in arm order.

    Raises:
        ValueError: The file is not such a mapping (the message names the file and entry).
    """
    import yaml

    data = yaml.safe_load(Path(config).read_text())
    if not isinstance(data, dict) or not data:
        raise ValueError(
            f"{config}: expected RMB's SpaceMouse YAML, a mapping of arm index -> "
            "{device_params: {path: /dev/hidrawN}}"
        )
    paths = []
    for arm in sorted(data, key=int):
        path = (data[arm] or {}).get("device_params", {}).get("path")
        if not isinstance(path, str):
            raise ValueError(f"{config}: arm {arm} has no device_params.path (a /dev/hidrawN)")
        paths.append(path)
    return tuple(paths)
