"""``--optimizer.type=adamw_fused``: LeRobot's AdamW with PyTorch's fused kernel.

LeRobot builds ``torch.optim.AdamW`` with its defaults, which on a CPU is the per-tensor loop
(neither ``foreach`` nor ``fused`` is used for CPU tensors): every step makes several temporaries
the size of each parameter. For the quick start's ACT (17 M parameters) that loop costs ~0.1 s
of CPU per step, the fused kernel a fraction of it (``benchmarks/optimizer_step.py``;
benchmarks/RESULTS.md, "Main job"). The update rule, its options and LeRobot's gradient
clipping are unchanged; only the kernel is, so results agree with ``adamw`` to float rounding.

Policies pick their optimizer through a preset, so using it means turning the preset off and
giving the preset's values explicitly, with a constant learning rate where the policy has no
scheduler (ACT); these ``lerobot-train`` arguments::

    --use_policy_training_preset=false --optimizer.type=adamw_fused
    --optimizer.lr=1e-4 --optimizer.weight_decay=1e-4
    --scheduler.type=constant_with_warmup --scheduler.num_warmup_steps=0

:func:`fused_adamw_args` builds those arguments. Importing :mod:`rmb_lerobot.optim.fused_adamw`
registers the type (``rmb_lerobot.registration`` does, so LeRobot's CLIs know it); this module
itself imports neither torch nor LeRobot, so command builders can use it.
"""

from __future__ import annotations

FUSED_ADAMW = "adamw_fused"  # the LeRobot optimizer type (rmb_lerobot.optim.fused_adamw)


def fused_adamw_args(lr: float, weight_decay: float) -> tuple[str, ...]:
    """``lerobot-train`` arguments that replace a policy's AdamW preset by :data:`FUSED_ADAMW`
    with the same learning rate and weight decay and a constant learning rate.

    Only for policies whose preset is AdamW without a scheduler (LeRobot's ACT): the preset is
    turned off, so a preset scheduler would be dropped.

    Args:
        lr: The preset's learning rate (ACT: ``--policy.optimizer_lr``).
        weight_decay: The preset's weight decay (ACT: ``--policy.optimizer_weight_decay``).

    Returns:
        The arguments.
    """
    return (
        "--use_policy_training_preset=false",
        f"--optimizer.type={FUSED_ADAMW}",
        f"--optimizer.lr={lr:g}",
        f"--optimizer.weight_decay={weight_decay:g}",
        "--scheduler.type=constant_with_warmup",
        "--scheduler.num_warmup_steps=0",
    )
