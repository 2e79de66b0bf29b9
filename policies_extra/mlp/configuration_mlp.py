"""Configuration of RMB's MLP policy (``--policy.type=mlp``).

Defaults follow RoboManipBaselines' ``TrainMlp`` (hidden layers [512, 512], state feature 512,
AdamW lr 1e-5 / weight decay 1e-4, MSE loss), except that the ResNet-18 backbone starts from
random weights: ``pretrained_backbone_weights`` defaults to None so training works offline
(RMB uses ImageNet weights; pass ``ResNet18_Weights.IMAGENET1K_V1`` to match it).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from lerobot.configs import NormalizationMode, PreTrainedConfig
from lerobot.optim import AdamWConfig


@PreTrainedConfig.register_subclass("mlp")
@dataclass
class MLPConfig(PreTrainedConfig):
    """State MLP + per-camera ResNet features -> MLP head -> a chunk of actions.

    Args:
        n_obs_steps: Observation frames stacked as input (current and past), as RMB's
            ``--n_obs_steps``.
        chunk_size: Actions predicted per forward pass (RMB's ``--n_action_steps``).
        n_action_steps: Actions of a chunk executed before the policy is queried again
            (<= chunk_size), as in LeRobot's ACT.
        vision_backbone: torchvision ResNet used per camera (its classifier is dropped).
        pretrained_backbone_weights: torchvision weights name, or None for random init.
        state_feature_dim: Width of the state embedding (Linear + ReLU).
        hidden_dims: Hidden widths of the MLP head.
    """

    n_obs_steps: int = 1
    chunk_size: int = 1
    n_action_steps: int = 1

    normalization_mapping: dict[str, NormalizationMode] = field(
        default_factory=lambda: {
            "VISUAL": NormalizationMode.MEAN_STD,
            "STATE": NormalizationMode.MEAN_STD,
            "ACTION": NormalizationMode.MEAN_STD,
        }
    )

    vision_backbone: str = "resnet18"
    pretrained_backbone_weights: str | None = None
    state_feature_dim: int = 512
    hidden_dims: list[int] = field(default_factory=lambda: [512, 512])

    optimizer_lr: float = 1e-5
    optimizer_weight_decay: float = 1e-4

    def __post_init__(self) -> None:
        super().__post_init__()
        if not self.vision_backbone.startswith("resnet"):
            raise ValueError(f"vision_backbone must be a ResNet, got {self.vision_backbone!r}")
        if self.n_obs_steps < 1 or self.chunk_size < 1:
            raise ValueError("n_obs_steps and chunk_size must be >= 1")
        if not 1 <= self.n_action_steps <= self.chunk_size:
            raise ValueError(
                f"n_action_steps ({self.n_action_steps}) must be in [1, chunk_size "
                f"({self.chunk_size})]"
            )

    def get_optimizer_preset(self) -> AdamWConfig:
        return AdamWConfig(lr=self.optimizer_lr, weight_decay=self.optimizer_weight_decay)

    def get_scheduler_preset(self) -> None:
        return None

    def validate_features(self) -> None:
        if not self.image_features and not self.robot_state_feature:
            raise ValueError("MLP needs observation.state and/or at least one image input.")
        if self.action_feature is None:
            raise ValueError("MLP needs an 'action' output feature.")
        not_rgb = [key for key, ft in self.image_features.items() if ft.shape[0] != 3]
        if not_rgb:  # the ResNet takes RGB; e.g. depth cameras must be left out of the inputs
            raise ValueError(f"MLP's ResNet needs 3-channel images, got {not_rgb}")

    @property
    def observation_delta_indices(self) -> list[int] | None:
        return list(range(1 - self.n_obs_steps, 1)) if self.n_obs_steps > 1 else None

    @property
    def action_delta_indices(self) -> list[int]:
        return list(range(self.chunk_size))

    @property
    def reward_delta_indices(self) -> None:
        return None
