"""LeRobot plugin entry point for rmb_lerobot.

LeRobot's ``lerobot-train``/``lerobot-eval``/... import every installed distribution whose name
starts with ``lerobot_env_`` (see ``lerobot.utils.import_utils.register_third_party_plugins``).
This distribution is ``lerobot_env_rmb``, so importing this module is how our env types and
policies become ``--env.type=`` / ``--policy.type=`` choices with no extra flags.
"""

from rmb_lerobot.registration import register_all

REGISTERED_MODULES = register_all()
