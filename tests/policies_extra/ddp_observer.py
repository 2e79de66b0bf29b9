"""``lerobot-train`` unchanged, with a recorder of what every DDP rank holds (test_distributed).

Launch it where ``lerobot-train`` would go (``accelerate launch ... ddp_observer.py <lerobot-train
arguments>``): it runs the same entry point as the ``lerobot-train`` console script and only
watches. LeRobot saves checkpoints from the main process alone, so this is how a test sees the other
ranks: when accelerate wraps the policy in ``DistributedDataParallel``, every rank saves the
wrapped module's state dict (after DDP's broadcast from rank 0) as
``$DDP_OBSERVER_DIR/rank<R>_start.safetensors``, and again at exit as ``rank<R>_end.safetensors``.
"""

from __future__ import annotations

import atexit
import os
import sys
from pathlib import Path

from safetensors.torch import save_file
from torch import nn
from torch.nn.parallel import DistributedDataParallel

OUT = Path(os.environ["DDP_OBSERVER_DIR"])
RANK = os.environ.get("RANK", "0")
_wrapped: list[nn.Module] = []
_ddp_init = DistributedDataParallel.__init__


def save_state(module: nn.Module, stage: str) -> None:
    state = {key: value.detach().clone() for key, value in module.state_dict().items()}
    save_file(state, OUT / f"rank{RANK}_{stage}.safetensors")


def recording_init(self: DistributedDataParallel, module: nn.Module, *args, **kwargs) -> None:
    _ddp_init(self, module, *args, **kwargs)
    _wrapped.append(module)
    save_state(module, "start")


def save_end_states() -> None:
    for module in _wrapped:
        save_state(module, "end")


if __name__ == "__main__":
    DistributedDataParallel.__init__ = recording_init
    atexit.register(save_end_states)
    from lerobot.scripts.lerobot_train import main

    sys.argv[0] = "lerobot-train"
    sys.exit(main())
