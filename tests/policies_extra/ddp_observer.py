"""``lerobot-train`` unchanged, with a recorder of what every DDP rank holds (test_distributed).

Launch it where ``lerobot-train`` would go (``accelerate launch ... ddp_observer.py <lerobot-train
arguments>``): it runs the same entry point as the ``lerobot-train`` console script and only
watches. LeRobot saves checkpoints from the main process alone, so this is how a test sees the other
ranks: when accelerate wraps the policy in ``DistributedDataParallel``, every rank saves the
wrapped module's state dict (after DDP's broadcast from rank 0) as
``$DDP_OBSERVER_DIR/rank<R>_start.safetensors``, and again at the end as
``rank<R>_end.safetensors``.

Each rank ends its process as soon as LeRobot's ``train()`` has called
``accelerator.end_training()`` (its last statement, after the final barrier and the checkpoint):
see :func:`end_training_then_exit` for why.
"""

from __future__ import annotations

import logging
import os
import sys
from pathlib import Path

from accelerate import Accelerator
from safetensors.torch import save_file
from torch import nn
from torch.nn.parallel import DistributedDataParallel

OUT = Path(os.environ["DDP_OBSERVER_DIR"])
RANK = os.environ.get("RANK", "0")
_wrapped: list[nn.Module] = []
_ddp_init = DistributedDataParallel.__init__
_end_training = Accelerator.end_training


def save_state(module: nn.Module, stage: str) -> None:
    state = {key: value.detach().clone() for key, value in module.state_dict().items()}
    save_file(state, OUT / f"rank{RANK}_{stage}.safetensors")


def recording_init(self: DistributedDataParallel, module: nn.Module, *args, **kwargs) -> None:
    _ddp_init(self, module, *args, **kwargs)
    _wrapped.append(module)
    save_state(module, "start")


def end_training_then_exit(self: Accelerator) -> None:
    """LeRobot's last call in ``train()``, then the end of this process without tear-down.

    LeRobot 0.6.1's ``train()`` destroys the process group (``end_training``) while its frame
    still holds the DDP-wrapped policy; the DDP Reducer keeps the gloo process group alive,
    so ``~ProcessGroupGloo`` runs later, when ``train()`` returns and its frame is freed, by
    which time the other rank may have exited. In about 1 run in 15 rank 0 then blocked for
    good joining a gloo thread in that destructor. Every rank has passed LeRobot's final
    barrier and the checkpoint is written when ``end_training`` returns, so nothing is left
    to do but exit; ``os._exit`` skips the destructors (Python's and gloo's) instead of
    racing them against the peer's exit.
    """
    _end_training(self)
    for module in _wrapped:
        save_state(module, "end")
    logging.shutdown()  # flush LeRobot's log handlers
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(0)


if __name__ == "__main__":
    DistributedDataParallel.__init__ = recording_init
    Accelerator.end_training = end_training_then_exit
    from lerobot.scripts.lerobot_train import main

    sys.argv[0] = "lerobot-train"
    main()
    sys.exit("lerobot-train returned without calling Accelerator.end_training()")
