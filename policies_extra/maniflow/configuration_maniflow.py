"""Configuration of ManiFlow (``--policy.type=maniflow``).

Yan et al., "ManiFlow: A General Robot Manipulation Policy via Consistency Flow Training",
CoRL 2025. A DiT-X transformer turns a chunk of noisy actions into a velocity: its action tokens
self-attend, cross-attend to observation tokens and are modulated by AdaLN from the flow time
(and the step size) and the pooled observation. The observation tokens come from RGB cameras (a
ResNet-18 with GroupNorm, trained from scratch) or from one depth camera's point cloud (the dp3
plugin's pipeline and PointNet), plus the state. Training mixes flow matching with consistency
training against an EMA copy; inference takes a few Euler steps.

Defaults are the paper's (DESIGN 7.5): 12 layers, 8 heads, 768 wide, horizon 16, 2 observation
steps, 75 % flow matching with t ~ Beta(1, 1.5), 25 % consistency, 10 Euler steps. That network
has 192.3 M trained parameters with the image encoder (one 32 x 32 camera, 7-D state/action;
11.2 M of them the ResNet-18; AdaLN's 9 x 768 x 768 per block is the largest part) and 180.9 M
with the point-cloud encoder; the EMA copy doubles what is stored. For a CPU pass
:data:`CPU_SIZE` as flags, ``--policy.n_layer=2 --policy.n_head=4 --policy.n_emb=64
--policy.resnet_width=16``: 0.95 M trained parameters with the image encoder (0.70 M ResNet),
0.31 M with the point cloud.

The point-cloud fields (``camera``, ``camera_fovy``, ``num_points``, crop ...) are inherited
from the dp3 plugin's :class:`PointCloudUnetConfig`, as are the optimizer and the observation /
action windows; its U-Net fields (``down_dims``, ``kernel_size``, ``n_groups``,
``diffusion_step_embed_dim``, ``use_film_scale_modulation``) are unused here.
"""

from __future__ import annotations

from dataclasses import dataclass

from lerobot.configs import PreTrainedConfig
from lerobot.configs.types import FeatureType

from rmb_lerobot import lerobot_names as N
from rmb_lerobot.policies_extra.dp3.configuration_dp3 import PointCloudUnetConfig

OBS_ENCODERS = ("image", "pointcloud")
# Flags for a network that trains on a CPU (the tests' and the CLI examples' size).
CPU_SIZE = {"n_layer": 2, "n_head": 4, "n_emb": 64, "resnet_width": 16}


@PreTrainedConfig.register_subclass("maniflow")
@dataclass
class ManiFlowConfig(PointCloudUnetConfig):
    """Images or a point cloud + state -> action chunk from a few consistency-flow steps.

    Args (besides :class:`PointCloudUnetConfig`'s):
        obs_encoder: ``"image"`` (every 3-channel camera input, one shared ResNet-18 with
            GroupNorm) or ``"pointcloud"`` (DP3's depth -> point cloud -> PointNet).
        n_layer / n_head / n_emb: The DiT-X transformer: blocks, attention heads, width.
        mlp_ratio: Hidden width of each block's MLP, in multiples of ``n_emb``.
        dropout: Dropout in attention and MLPs.
        resnet_width: Channels of the ResNet's first stage (64: ResNet-18; smaller for CPUs,
            the stages double it as in ResNet-18).
        pool_image_features: One token per camera and frame (the ResNet's average-pooled
            features) instead of one per cell of its last feature map (stride 32, e.g. 2 x 2 for
            64 x 64 images; the authors' setting, ``global_pool: ''``).
        groupnorm_channels: Channels per GroupNorm group replacing ResNet's BatchNorm (16 as
            Diffusion Policy's ``replace_bn_with_gn``).
        flow_batch_ratio: Share of each batch trained by flow matching; the rest by
            consistency training.
        flow_t_alpha / flow_t_beta: Flow-matching times t ~ Beta(alpha, beta); t = 0 is noise,
            t = 1 the actions.
        consistency_time_steps: Consistency training draws t from {0, 1/n, ..., (n-1)/n}
            (the authors' ``denoise_timesteps``, 10).
        num_inference_steps: Euler steps from noise to actions.
        time_scale: The sinusoidal time / step embeddings see ``t * time_scale`` (DiT's
            range of diffusion steps; ours, the authors embed t in [0, 1]).
        optimizer_*: The authors' AdamW (lr 1e-4, betas (0.9, 0.95), weight decay 1e-3), cosine
            schedule with 500 warm-up steps.
        ema_power / ema_max_decay: The EMA copy (consistency targets and inference) is updated
            after each optimizer step (``policy.update()``), decay 1 - (1 + k) ** -power capped.
    """

    obs_encoder: str = "image"

    n_layer: int = 12
    n_head: int = 8
    n_emb: int = 768
    mlp_ratio: float = 4.0
    dropout: float = 0.0
    resnet_width: int = 64
    pool_image_features: bool = False
    groupnorm_channels: int = 16

    flow_batch_ratio: float = 0.75
    flow_t_alpha: float = 1.0
    flow_t_beta: float = 1.5
    consistency_time_steps: int = 10
    num_inference_steps: int = 10
    time_scale: float = 1000.0

    ema_power: float = 0.75
    ema_max_decay: float = 0.9999

    optimizer_betas: tuple[float, float] = (0.9, 0.95)
    optimizer_weight_decay: float = 1e-3

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.obs_encoder not in OBS_ENCODERS:
            raise ValueError(f"obs_encoder must be one of {OBS_ENCODERS}, got {self.obs_encoder!r}")
        if self.n_emb % self.n_head:
            raise ValueError(f"n_emb ({self.n_emb}) must be a multiple of n_head ({self.n_head})")
        if self.n_layer < 1 or self.num_inference_steps < 1:
            raise ValueError(
                f"n_layer ({self.n_layer}) and num_inference_steps "
                f"({self.num_inference_steps}) must be >= 1"
            )
        if not 0.0 <= self.flow_batch_ratio <= 1.0:
            raise ValueError(f"flow_batch_ratio must be in [0, 1], got {self.flow_batch_ratio}")
        if self.resnet_width % self.groupnorm_channels:
            raise ValueError(
                f"resnet_width ({self.resnet_width}) must be a multiple of groupnorm_channels "
                f"({self.groupnorm_channels})"
            )
        if self.consistency_time_steps < 1:
            raise ValueError(
                f"consistency_time_steps must be >= 1, got {self.consistency_time_steps}"
            )
        if not 0.0 <= self.ema_max_decay < 1.0:
            raise ValueError(f"ema_max_decay must be in [0, 1), got {self.ema_max_decay}")

    @property
    def image_keys(self) -> tuple[str, ...]:
        """The RGB cameras the image encoder reads (depth cameras excluded)."""
        return tuple(
            key
            for key, ft in self.input_features.items()
            if ft.type is FeatureType.VISUAL
            and ft.shape[0] == 3
            and not key.endswith(N.DEPTH_CAMERA_SUFFIX)
        )

    def validate_features(self) -> None:
        if self.obs_encoder == "pointcloud":
            super().validate_features()
            return
        if not self.robot_state_feature:
            raise ValueError("maniflow needs 'observation.state'.")
        if self.action_feature is None:
            raise ValueError("maniflow needs an 'action' output feature.")
        if not self.image_keys:
            raise ValueError(
                "maniflow with obs_encoder='image' needs an RGB camera input (3, H, W); inputs: "
                f"{sorted(self.input_features)}"
            )
