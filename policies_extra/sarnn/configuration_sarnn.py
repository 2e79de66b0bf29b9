"""Configuration of SARNN, the Spatial Attention RNN (``--policy.type=sarnn``).

Ichiwara et al., ICRA 2022, and Ito et al., Science Robotics 2022, as implemented in
RoboManipBaselines (``SarnnPolicy`` / ``TrainSarnn``); defaults are RMB's (5 attention points
per camera, LSTM of 50 units, 64x64 images, skip 6, image/attention loss scales 0.1, Adam lr 1e-4
eps 1e-7, state noise 0.2 and image noise 0.02 on the inputs).

Sequences come from LeRobot's delta indices: one training sample is a window of
``sequence_length`` LSTM steps, ``frame_skip`` dataset frames apart, starting at the sampled
frame. Observations cover steps 0..L (the extra frame is the image/keypoint target of the last
step) and actions steps 1..L: the action learnt at step k is the command at the next step's
frame, i.e. the policy predicts the next commanded joint positions and sends them, held for
``frame_skip`` env steps, as RMB's rollout does. LeRobot's ``*_is_pad`` masks drop the steps
past an episode's end. RMB trains on whole episodes from their start; a window at least as long
as the episodes (in steps) is the closest equivalent.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from lerobot.configs import NormalizationMode, PreTrainedConfig
from lerobot.optim import AdamConfig


@PreTrainedConfig.register_subclass("sarnn")
@dataclass
class SARNNConfig(PreTrainedConfig):
    """Per-camera spatial-softmax keypoints + state -> LSTM -> next state, keypoints and image.

    Args:
        sequence_length: LSTM steps per training window (truncated back-propagation length).
        frame_skip: Dataset frames (= env steps) per LSTM step; RMB's ``skip``.
        image_size: (height, width) the images are resized to inside the model, or None to
            use them as they come (RMB crops and resizes to 64x64).
        num_keypoints: Attention points per camera (RMB's ``num_attentions``).
        lstm_hidden_dim: LSTM units.
        encoder_channels: Channels of the first two 3x3 convolutions of both encoders (the third
            outputs ``num_keypoints`` channels); the image decoder mirrors them.
        softmax_temperature: Spatial-softmax temperature (small = sharp attention).
        heatmap_size: Width of the Gaussian heatmaps drawn at the predicted keypoints.
        image_loss_weight: Scale of the image loss (RMB's image scale).
        keypoint_loss_weight: Scale of the keypoint loss (RMB's attention scale).
        keypoint_loss_warmup_steps: Training steps over which the keypoint loss weight ramps
            up along an S curve (RMB's ``LossScheduler(decay_end=1000, curve_name="s")``).
        state_noise_std: Standard deviation of the Gaussian noise added to the state during
            training only (the targets stay clean), as RMB's augmentation.
        image_noise_std: The same for the images.
    """

    sequence_length: int = 20
    frame_skip: int = 6

    normalization_mapping: dict[str, NormalizationMode] = field(
        default_factory=lambda: {
            "VISUAL": NormalizationMode.IDENTITY,
            "STATE": NormalizationMode.MEAN_STD,
            "ACTION": NormalizationMode.MEAN_STD,
        }
    )

    image_size: tuple[int, int] | None = (64, 64)
    num_keypoints: int = 5
    lstm_hidden_dim: int = 50
    encoder_channels: tuple[int, int] = (16, 32)
    softmax_temperature: float = 1e-4
    heatmap_size: float = 0.1

    image_loss_weight: float = 0.1
    keypoint_loss_weight: float = 0.1
    keypoint_loss_warmup_steps: int = 1000
    state_noise_std: float = 0.2
    image_noise_std: float = 0.02

    optimizer_lr: float = 1e-4
    optimizer_eps: float = 1e-7

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.sequence_length < 1 or self.frame_skip < 1:
            raise ValueError("sequence_length and frame_skip must be >= 1")
        if self.image_size is not None and min(self.image_size) <= 6:
            raise ValueError(
                f"image_size must exceed 6 pixels (3 valid 3x3 convs): {self.image_size}"
            )

    def get_optimizer_preset(self) -> AdamConfig:
        return AdamConfig(lr=self.optimizer_lr, eps=self.optimizer_eps)

    def get_scheduler_preset(self) -> None:
        return None

    def validate_features(self) -> None:
        if not self.robot_state_feature:
            raise ValueError("SARNN needs 'observation.state' (the state it predicts).")
        if not self.image_features:
            raise ValueError("SARNN needs at least one camera ('observation.images.<name>').")
        if self.action_feature is None:
            raise ValueError("SARNN needs an 'action' output feature.")

    @property
    def observation_delta_indices(self) -> list[int]:
        return [k * self.frame_skip for k in range(self.sequence_length + 1)]

    @property
    def action_delta_indices(self) -> list[int]:
        return [k * self.frame_skip for k in range(1, self.sequence_length + 1)]

    @property
    def reward_delta_indices(self) -> None:
        return None
