"""Configuration of Flow Policy (``--policy.type=flow_policy``).

Zhang et al., "FlowPolicy: Enabling Fast and Robust 3D Flow-based Policy via Consistency Flow
Matching for Robot Manipulation", AAAI 2025. The networks are DP3's (point cloud from one depth
camera -> PointNet, state -> MLP, both the FiLM condition of a 1-D U-Net; see
:class:`~rmb_lerobot.policies_extra.dp3.configuration_dp3.PointCloudUnetConfig`, whose fields and
checks this config inherits); the U-Net predicts a velocity from noise to actions trained with
consistency flow matching, so one Euler step from noise gives an action chunk.

Defaults are RMB's (``TrainFlowPolicy.setup_policy``): horizon 8, 2 observation steps,
4 executed actions, 2 segments, eps 1e-2, delta 1e-2, alpha 1e-5, boundary 1, one inference
step, an EMA copy for inference (power 0.75, max decay 0.9999), AdamW lr 1e-4 with a cosine
schedule and 500 warm-up steps. As in the dp3 plugin, the U-Net is smaller than RMB's so that it
trains on a CPU: ``down_dims`` (64, 128, 256) here, RMB/paper (512, 1024, 2048); pass
``--policy.down_dims=[512,1024,2048]`` for the paper's size.
"""

from __future__ import annotations

from dataclasses import dataclass

from lerobot.configs import PreTrainedConfig

from rmb_lerobot.policies_extra.dp3.configuration_dp3 import PointCloudUnetConfig


@PreTrainedConfig.register_subclass("flow_policy")
@dataclass
class FlowPolicyConfig(PointCloudUnetConfig):
    """Point cloud + state -> action chunk in one (or a few) consistency-flow steps.

    Args (besides :class:`PointCloudUnetConfig`'s):
        num_segments: The time axis [0, 1] is cut into this many segments; within each, the
            velocity is trained to be constant along the straight noise -> action path, so one
            Euler step per segment is exact ("multi-segment" consistency flow matching).
        eps: Earliest flow time, for training samples and the first sampling step (t = 0 is
            pure noise, t = 1 the actions).
        delta: Gap between the two times whose segment-end predictions must agree.
        alpha: Weight of the velocity-consistency term against the endpoint term.
        boundary: Times at or past this use the true segment end as the target (1: only the
            end of the last segment).
        num_inference_steps: Euler steps from noise to actions (1: the paper's one-step
            inference).
        timestep_scale: The U-Net's sinusoidal time embedding sees ``t * timestep_scale``;
            FlowPolicy uses 99, the range of the DDPM steps the embedding was made for.
    """

    horizon: int = 8
    n_action_steps: int = 4

    num_segments: int = 2
    eps: float = 1e-2
    delta: float = 1e-2
    alpha: float = 1e-5
    boundary: float = 1.0
    num_inference_steps: int = 1
    timestep_scale: float = 99.0

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.num_segments < 1 or self.num_inference_steps < 1:
            raise ValueError(
                f"num_segments ({self.num_segments}) and num_inference_steps "
                f"({self.num_inference_steps}) must be >= 1"
            )
        if not 0.0 <= self.eps < 1.0:
            raise ValueError(f"eps must be in [0, 1), got {self.eps}")
        if not 0.0 < self.delta < 1.0:
            raise ValueError(f"delta must be in (0, 1), got {self.delta}")
