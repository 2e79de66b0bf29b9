"""SARNN (Spatial Attention RNN) on LeRobot's policy API.

Architecture as RoboManipBaselines' ``SarnnPolicy`` (after Ichiwara et al. ICRA 2022 / EIPL):
per camera, a 3-layer convolutional attention encoder whose spatial softmax gives K keypoints
and a 3-layer image feature encoder; an LSTM cell over [state, keypoints of every camera];
decoders for the next state, the next keypoints, and the next image (Gaussian heatmaps at the
predicted keypoints times the image features, through 3 transposed convolutions).

Only the LSTM is sequential: the encoders run on all frames of a window at once, and the
decoders on all LSTM outputs at once, so training is one batched pass per window. At rollout
the policy steps the LSTM every ``frame_skip`` calls and holds the predicted state (the
command) in between; image decoding is skipped because only the state is sent.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import torch
import torch.nn.functional as F
from lerobot.policies.pretrained import PreTrainedPolicy
from lerobot.utils.constants import ACTION, OBS_STATE
from torch import Tensor, nn

from .configuration_sarnn import SARNNConfig

NEGATIVE_SLOPE = 0.3  # of every LeakyReLU, as RMB/EIPL


class SARNNPolicy(PreTrainedPolicy):
    """Spatial Attention RNN: predicts the next state (sent as the command) from state + images."""

    config_class = SARNNConfig
    name = "sarnn"

    def __init__(self, config: SARNNConfig, **kwargs):
        """``kwargs`` (e.g. ``dataset_meta`` from ``make_policy``) are not needed here."""
        super().__init__(config)
        config.validate_features()
        self.config = config
        self.model = SARNN(config)
        # Training steps seen, for the keypoint-loss warm-up (saved, so resuming continues it).
        self.register_buffer("train_steps", torch.zeros((), dtype=torch.long))
        self.reset()

    def get_optim_params(self) -> list[nn.Parameter]:
        return [p for p in self.parameters() if p.requires_grad]

    def reset(self) -> None:
        """Start a new episode: zero LSTM state, no held command."""
        self._lstm_state: tuple[Tensor, Tensor] | None = None
        self._held_action: Tensor | None = None
        self._env_step = 0

    @torch.no_grad()
    def predict_action_chunk(self, batch: dict[str, Tensor], **kwargs) -> Tensor:
        """Advance the LSTM by one step; returns the next command as a (B, 1, action_dim) chunk.

        Stateful: the recurrent state carries over between calls until :meth:`reset`.
        """
        self.eval()
        images = [self.model.resize(batch[key]) for key in self.config.image_features]
        keypoints = [
            branch.keypoints(img) for branch, img in zip(self.model.cameras, images, strict=True)
        ]
        self._lstm_state = self.model.lstm(
            self.model.lstm_input(batch[OBS_STATE], keypoints), self._lstm_state
        )
        return self.model.state_decoder(self._lstm_state[0]).unsqueeze(1)

    @torch.no_grad()
    def select_action(self, batch: dict[str, Tensor], **kwargs) -> Tensor:
        """Query the LSTM every ``frame_skip`` env steps and hold its command in between."""
        if self._env_step % self.config.frame_skip == 0 or self._held_action is None:
            self._held_action = self.predict_action_chunk(batch)[:, 0]
        self._env_step += 1
        return self._held_action

    def forward(self, batch: dict[str, Tensor]) -> tuple[Tensor, dict]:
        """Loss over a window: state MSE + image reconstruction + keypoint prediction.

        ``batch``: ``observation.state`` (B, L+1, D), each image (B, L+1, C, H, W), ``action``
        (B, L, A) = the command at each step's next frame, ``action_is_pad`` (B, L).
        """
        cfg = self.config
        state = batch[OBS_STATE][:, :-1]
        targets = batch[ACTION]
        steps = targets.shape[1]
        is_pad = batch.get(f"{ACTION}_is_pad")
        valid = torch.ones(targets.shape[:2], device=targets.device) if is_pad is None else ~is_pad
        valid = valid.float()

        if self.training:
            state = state + cfg.state_noise_std * torch.randn_like(state)
        clean = [self.model.resize(batch[key][:, : steps + 1]) for key in cfg.image_features]
        noisy = [self._add_image_noise(images) for images in clean]
        out = self.model.run_sequence(state, noisy)

        state_loss = masked_mean(F.mse_loss(out.states, targets, reduction="none"), valid)
        image_loss = sum(
            masked_mean(F.mse_loss(pred, target[:, 1:], reduction="none"), valid)
            for pred, target in zip(out.images, clean, strict=True)
        )
        keypoint_loss = sum(
            masked_mean(F.mse_loss(pred, enc[:, 1:], reduction="none"), valid)
            for pred, enc in zip(out.next_keypoints, out.keypoints, strict=True)
        )
        keypoint_weight = cfg.keypoint_loss_weight * self._keypoint_ramp()
        loss = state_loss + cfg.image_loss_weight * image_loss + keypoint_weight * keypoint_loss
        if self.training:
            self.train_steps += 1
        return loss, {
            "state_loss": state_loss.item(),
            "image_loss": image_loss.item(),
            "keypoint_loss": keypoint_loss.item(),
            "keypoint_weight": keypoint_weight,
        }

    def _add_image_noise(self, images: Tensor) -> Tensor:
        if not self.training or self.config.image_noise_std <= 0:
            return images
        return (images + self.config.image_noise_std * torch.randn_like(images)).clamp(0, 1)

    def _keypoint_ramp(self) -> float:
        """RMB's S-curve 0 -> 1 over ``keypoint_loss_warmup_steps`` training steps."""
        total = self.config.keypoint_loss_warmup_steps
        if total <= 0:
            return 1.0
        t = min(int(self.train_steps) / total, 1.0)
        return t - math.sin(2 * math.pi * t) / (2 * math.pi)


def masked_mean(err: Tensor, valid: Tensor) -> Tensor:
    """Mean of ``err`` (B, L, ...) over the valid (B, L) steps and all trailing dimensions."""
    per_step = err.flatten(2).mean(-1)
    return (per_step * valid).sum() / valid.sum().clamp_min(1)


class SpatialSoftmax(nn.Module):
    """Expected (x, y) in [0, 1] of each channel's softmax over pixels (Finn et al. 2016)."""

    def __init__(self, height: int, width: int, temperature: float):
        super().__init__()
        self.temperature = temperature
        self.register_buffer("grid", pixel_grid(height, width), persistent=False)

    def forward(self, features: Tensor) -> Tensor:
        attention = torch.softmax(features.flatten(2) / self.temperature, dim=-1)
        return attention @ self.grid  # (B, K, 2)


class InverseSpatialSoftmax(nn.Module):
    """Gaussian heatmaps centred on (x, y) keypoints in [0, 1] (Ichiwara et al. 2022)."""

    def __init__(self, height: int, width: int, heatmap_size: float):
        super().__init__()
        self.shape = (height, width)
        self.heatmap_size = heatmap_size
        self.register_buffer("grid", pixel_grid(height, width), persistent=False)

    def forward(self, keypoints: Tensor) -> Tensor:
        sq_dist = (self.grid - keypoints.unsqueeze(-2)).pow(2).sum(-1)  # (B, K, H*W)
        return torch.exp(-sq_dist / self.heatmap_size).unflatten(-1, self.shape)


def pixel_grid(height: int, width: int) -> Tensor:
    """(H*W, 2) normalized (x, y) of every pixel, row-major."""
    ys, xs = torch.meshgrid(
        torch.linspace(0, 1, height), torch.linspace(0, 1, width), indexing="ij"
    )
    return torch.stack([xs.flatten(), ys.flatten()], dim=-1)


def conv_stack(
    channels: list[int], transposed: bool = False, last_act: bool = True
) -> nn.Sequential:
    """Valid 3x3 convolutions (or their transposes) with LeakyReLU(0.3) between them."""
    conv = nn.ConvTranspose2d if transposed else nn.Conv2d
    layers: list[nn.Module] = []
    for i, (c_in, c_out) in enumerate(itertools.pairwise(channels)):
        layers.append(conv(c_in, c_out, kernel_size=3, stride=1, padding=0))
        if last_act or i < len(channels) - 2:
            layers.append(nn.LeakyReLU(NEGATIVE_SLOPE))
    return nn.Sequential(*layers)


class CameraBranch(nn.Module):
    """Encoders and decoders of one camera."""

    def __init__(self, config: SARNNConfig, channels: int, height: int, width: int):
        super().__init__()
        k = config.num_keypoints
        c1, c2 = config.encoder_channels
        h, w = height - 6, width - 6  # three valid 3x3 convolutions
        self.attention_encoder = conv_stack([channels, c1, c2, k])
        self.spatial_softmax = SpatialSoftmax(h, w, config.softmax_temperature)
        self.feature_encoder = conv_stack([channels, c1, c2, k])
        self.keypoint_decoder = nn.Sequential(
            nn.Linear(config.lstm_hidden_dim, 2 * k), nn.LeakyReLU(NEGATIVE_SLOPE)
        )
        self.heatmap = InverseSpatialSoftmax(h, w, config.heatmap_size)
        self.image_decoder = conv_stack([k, c2, c1, channels], transposed=True, last_act=False)

    def keypoints(self, images: Tensor) -> Tensor:
        """(N, C, H, W) -> (N, K, 2)."""
        return self.spatial_softmax(self.attention_encoder(channels_last(images)))

    def features(self, images: Tensor) -> Tensor:
        """(N, C, H, W) -> (N, K, H - 6, W - 6)."""
        return self.feature_encoder(channels_last(images))

    def decode_image(self, hidden: Tensor, features: Tensor) -> tuple[Tensor, Tensor]:
        """Next keypoints (N, K, 2) and next image (N, C, H, W) from LSTM outputs (N, hidden)."""
        next_keypoints = self.keypoint_decoder(hidden).unflatten(-1, (-1, 2))
        masked = channels_last(self.heatmap(next_keypoints) * features)
        return next_keypoints, self.image_decoder(masked)


def channels_last(images: Tensor) -> Tensor:
    """NHWC layout: oneDNN's convolutions (forward and backward) run ~1.4x faster on CPU."""
    return images.contiguous(memory_format=torch.channels_last)


@dataclass
class SequenceOutput:
    """What one window produces; tensors are (B, L, ...), lists have one entry per camera."""

    states: Tensor  # predicted next states (the commands)
    keypoints: list[Tensor]  # encoded from the frames, (B, L+1, K, 2)
    next_keypoints: list[Tensor]  # predicted for the next frame, (B, L, K, 2)
    images: list[Tensor]  # predicted next images, (B, L, C, H, W)


class SARNN(nn.Module):
    """The network: camera branches around one LSTM cell."""

    def __init__(self, config: SARNNConfig):
        super().__init__()
        self.config = config
        self.cameras = nn.ModuleList(
            CameraBranch(config, ft.shape[0], *(config.image_size or ft.shape[1:]))
            for ft in config.image_features.values()
        )
        state_dim = config.robot_state_feature.shape[0]
        lstm_in = state_dim + 2 * config.num_keypoints * len(self.cameras)
        self.lstm = nn.LSTMCell(lstm_in, config.lstm_hidden_dim)
        self.state_decoder = nn.Linear(config.lstm_hidden_dim, config.action_feature.shape[0])
        self.apply(init_weights)

    def resize(self, images: Tensor) -> Tensor:
        """Resize (..., C, H, W) images to ``image_size`` (antialiased bilinear)."""
        size = self.config.image_size
        if size is None or tuple(images.shape[-2:]) == tuple(size):
            return images
        flat = F.interpolate(
            images.flatten(0, -4), size=tuple(size), mode="bilinear", antialias=True
        )
        return flat.unflatten(0, images.shape[:-3])

    def lstm_input(self, state: Tensor, keypoints: list[Tensor]) -> Tensor:
        return torch.cat([state, *(kp.flatten(-2) for kp in keypoints)], dim=-1)

    def run_sequence(self, state: Tensor, images: list[Tensor]) -> SequenceOutput:
        """state (B, L, D); images per camera (B, L+1, C, H, W), resized."""
        batch, steps = state.shape[:2]
        keypoints, features = [], []
        for branch, seq in zip(self.cameras, images, strict=True):
            keypoints.append(branch.keypoints(seq.flatten(0, 1)).unflatten(0, (batch, steps + 1)))
            features.append(branch.features(seq[:, :steps].flatten(0, 1)))

        inputs = self.lstm_input(state, [kp[:, :steps] for kp in keypoints])
        lstm_state, hidden = None, []
        for k in range(steps):
            lstm_state = self.lstm(inputs[:, k], lstm_state)
            hidden.append(lstm_state[0])
        hidden = torch.stack(hidden, dim=1).flatten(0, 1)  # (B*L, hidden)

        next_keypoints, next_images = [], []
        for branch, feats in zip(self.cameras, features, strict=True):
            kp, img = branch.decode_image(hidden, feats)
            next_keypoints.append(kp.unflatten(0, (batch, steps)))
            next_images.append(img.unflatten(0, (batch, steps)))
        states = self.state_decoder(hidden).unflatten(0, (batch, steps))
        return SequenceOutput(states, keypoints, next_keypoints, next_images)


def init_weights(module: nn.Module) -> None:
    """Keras-like initialisation, as RMB/EIPL."""
    if isinstance(module, nn.LSTMCell):
        nn.init.xavier_uniform_(module.weight_ih)
        nn.init.orthogonal_(module.weight_hh)
        nn.init.zeros_(module.bias_ih)
        nn.init.zeros_(module.bias_hh)
    elif isinstance(module, nn.Conv2d | nn.ConvTranspose2d | nn.Linear):
        nn.init.xavier_uniform_(module.weight)
        nn.init.zeros_(module.bias)
