"""What we add to LeRobot, and the one place that registers it.

LeRobot's CLIs call ``register_third_party_plugins()``, which imports every installed
distribution whose name starts with ``lerobot_env_``; ours is ``lerobot_env_rmb`` and its
import calls :func:`register_all`. Modules listed here register LeRobot ``EnvConfig`` /
``PreTrainedConfig`` / ``RobotConfig`` / ``TeleoperatorConfig`` / ``CameraConfig`` /
``OptimizerConfig`` subclasses
(``@EnvConfig.register_subclass(...)``) when imported, so adding an env family, a policy or a
device means adding its module name to one of these tuples.
"""

from __future__ import annotations

import importlib

# Modules whose import registers LeRobot env types (``--env.type=rmb_...``).
ENV_CONFIG_MODULES: tuple[str, ...] = ("rmb_lerobot.envs.lerobot_config",)
# Modules whose import registers LeRobot robot, teleoperator and camera types
# (``--robot.type=rmb_ur5e``, ``--teleop.type=rmb_scripted``, camera ``type: rmb_twin``).
DEVICE_CONFIG_MODULES: tuple[str, ...] = (
    "rmb_lerobot.envs.real.lerobot_devices",
    "rmb_lerobot.envs.real.cameras.config_twin",
    "rmb_lerobot.envs.real.lerobot_devices.config_teleop_devices",
)
# Modules whose import registers LeRobot policy types (``--policy.type=...``).
POLICY_CONFIG_MODULES: tuple[str, ...] = (
    "rmb_lerobot.policies_extra.mlp.configuration_mlp",
    "rmb_lerobot.policies_extra.sarnn.configuration_sarnn",
    "rmb_lerobot.policies_extra.dp3.configuration_dp3",
    "rmb_lerobot.policies_extra.flow_policy.configuration_flow_policy",
    "rmb_lerobot.policies_extra.mt_act.configuration_mt_act",
    "rmb_lerobot.policies_extra.maniflow.configuration_maniflow",
)

# Modules whose import registers LeRobot optimizer types (``--optimizer.type=adamw_fused``).
OPTIMIZER_CONFIG_MODULES: tuple[str, ...] = ("rmb_lerobot.optim.fused_adamw",)

ENV_TYPE_PREFIX = "rmb_"


def register_all(
    env_modules: tuple[str, ...] = ENV_CONFIG_MODULES,
    policy_modules: tuple[str, ...] = POLICY_CONFIG_MODULES,
    device_modules: tuple[str, ...] = DEVICE_CONFIG_MODULES,
    optimizer_modules: tuple[str, ...] = OPTIMIZER_CONFIG_MODULES,
) -> list[str]:
    """Import every registering module (idempotent); returns the module names imported.

    An import error propagates: LeRobot only logs plugin import failures, so failing loudly
    here is what makes a broken registration visible in our own tests.
    """
    imported = []
    for name in (*env_modules, *policy_modules, *device_modules, *optimizer_modules):
        importlib.import_module(name)
        imported.append(name)
    return imported


def registered_env_types() -> list[str]:
    """LeRobot env types this package provides (``rmb_*``), as LeRobot's CLI would list them."""
    from lerobot.envs.configs import EnvConfig

    return sorted(n for n in EnvConfig.get_known_choices() if n.startswith(ENV_TYPE_PREFIX))


def registered_policy_types() -> list[str]:
    """LeRobot policy types registered by the modules in :data:`POLICY_CONFIG_MODULES`."""
    from lerobot.configs.policies import PreTrainedConfig

    ours = set(POLICY_CONFIG_MODULES)
    return sorted(
        name for name, cls in PreTrainedConfig.get_known_choices().items() if cls.__module__ in ours
    )
