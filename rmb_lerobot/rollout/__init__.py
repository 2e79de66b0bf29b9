"""Interactive language-instruction rollout over a local socket.

``rmb-rollout POLICY_PATH --env.type=... --listen unix:/tmp/rmb.sock`` waits for one
instruction per episode and runs the language-conditioned policy with it; ``done`` ends the
episode early. The wire protocol is in :mod:`.protocol`, the server in :mod:`.server`, a
client in :mod:`.client`, the LeRobot policy/env glue in :mod:`.lerobot_policy` (imported
lazily: it pulls in torch and LeRobot).
"""

from rmb_lerobot.rollout.client import RolloutClient, RolloutError
from rmb_lerobot.rollout.protocol import Address
from rmb_lerobot.rollout.server import (
    EpisodeResult,
    RolloutPolicy,
    RolloutServer,
    stop_on_signals,
    takes_instruction,
)

__all__ = [
    "Address",
    "EpisodeResult",
    "RolloutClient",
    "RolloutError",
    "RolloutPolicy",
    "RolloutServer",
    "stop_on_signals",
    "takes_instruction",
]
