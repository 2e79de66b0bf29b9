"""RMB's MLP policy (``MlpPolicy``) on LeRobot's policy API.

The network is RMB's: the state (``n_obs_steps`` frames, flattened) goes through Linear + ReLU,
every camera frame through one shared ResNet (classifier removed, global-average-pooled
features), and the concatenation through an MLP head that outputs ``chunk_size`` actions.
Execution of a chunk follows LeRobot's ACT (an action queue refilled every ``n_action_steps``).
"""

from __future__ import annotations

import itertools
from collections import deque

import torch
import torch.nn.functional as F
import torchvision
from lerobot.policies.pretrained import PreTrainedPolicy
from lerobot.policies.utils import populate_queues
from lerobot.utils.constants import ACTION, OBS_STATE
from torch import Tensor, nn
from torchvision.ops.misc import FrozenBatchNorm2d

from .configuration_mlp import MLPConfig


class MLPPolicy(PreTrainedPolicy):
    """Multilayer-perceptron behaviour cloning policy (RoboManipBaselines' ``Mlp``)."""

    config_class = MLPConfig
    name = "mlp"

    def __init__(self, config: MLPConfig, **kwargs):
        """``kwargs`` (e.g. ``dataset_meta`` from ``make_policy``) are not needed here."""
        super().__init__(config)
        config.validate_features()
        self.config = config
        self.model = MLPModel(config)
        self.reset()

    def get_optim_params(self) -> list[nn.Parameter]:
        return [p for p in self.parameters() if p.requires_grad]

    def reset(self) -> None:
        """Forget observation history and queued actions; call on every env reset."""
        self._obs_queues = {key: deque(maxlen=self.config.n_obs_steps) for key in self._obs_keys}
        self._action_queue: deque[Tensor] = deque(maxlen=self.config.n_action_steps)

    @property
    def _obs_keys(self) -> list[str]:
        keys = [OBS_STATE] if self.config.robot_state_feature else []
        return keys + list(self.config.image_features)

    @torch.no_grad()
    def predict_action_chunk(self, batch: dict[str, Tensor], **kwargs) -> Tensor:
        """(B, chunk_size, action_dim) from one observation or (B, n_obs_steps, ...) stacks."""
        self.eval()
        return self.model(*self._inputs(batch))

    @torch.no_grad()
    def select_action(self, batch: dict[str, Tensor], **kwargs) -> Tensor:
        """One action per call; the model runs when the queue of ``n_action_steps`` is empty."""
        self.eval()
        self._obs_queues = populate_queues(self._obs_queues, batch)
        if not self._action_queue:
            stacked = {key: torch.stack(list(q), dim=1) for key, q in self._obs_queues.items()}
            chunk = self.predict_action_chunk(stacked)[:, : self.config.n_action_steps]
            self._action_queue.extend(chunk.transpose(0, 1))
        return self._action_queue.popleft()

    def forward(self, batch: dict[str, Tensor]) -> tuple[Tensor, dict]:
        """Masked MSE over the action chunk (padding past an episode's end is ignored)."""
        actions_hat = self.model(*self._inputs(batch))
        target = batch[ACTION]
        if target.ndim == 2:
            target = target.unsqueeze(1)
        err = F.mse_loss(actions_hat, target, reduction="none")
        is_pad = batch.get(f"{ACTION}_is_pad")
        valid = (
            torch.ones_like(err[..., 0], dtype=torch.bool) if is_pad is None else ~is_pad
        ).unsqueeze(-1)
        loss = (err * valid).sum() / (valid.sum() * err.shape[-1]).clamp_min(1)
        return loss, {"mse_loss": loss.item()}

    def _inputs(self, batch: dict[str, Tensor]) -> tuple[Tensor | None, Tensor | None]:
        """State as (B, T, D) and images as (B, T, N_cameras, C, H, W); T = n_obs_steps."""
        state = None
        if self.config.robot_state_feature:
            state = batch[OBS_STATE]
            state = state.unsqueeze(1) if state.ndim == 2 else state
        images = None
        if self.config.image_features:
            images = torch.stack([batch[key] for key in self.config.image_features], dim=-4)
            images = images.unsqueeze(1) if images.ndim == 5 else images
        return state, images


class MLPModel(nn.Module):
    """State embedding + shared ResNet image features -> MLP -> (B, chunk_size, action_dim)."""

    def __init__(self, config: MLPConfig):
        super().__init__()
        self.config = config
        in_dim = 0
        if config.robot_state_feature:
            state_dim = config.robot_state_feature.shape[0] * config.n_obs_steps
            self.state_encoder = nn.Sequential(
                nn.Linear(state_dim, config.state_feature_dim), nn.ReLU()
            )
            in_dim += config.state_feature_dim
        if config.image_features:
            resnet = getattr(torchvision.models, config.vision_backbone)(
                weights=config.pretrained_backbone_weights, norm_layer=FrozenBatchNorm2d
            )
            self.backbone = nn.Sequential(*list(resnet.children())[:-1])  # up to avgpool
            n_frames = len(config.image_features) * config.n_obs_steps
            in_dim += resnet.fc.in_features * n_frames
        action_dim = config.action_feature.shape[0]
        dims = [in_dim, *config.hidden_dims, action_dim * config.chunk_size]
        layers: list[nn.Module] = []
        for i, (d_in, d_out) in enumerate(itertools.pairwise(dims)):
            layers.append(nn.Linear(d_in, d_out))
            if i < len(dims) - 2:
                layers.append(nn.ReLU())
        self.head = nn.Sequential(*layers)
        for module in [*self.head.modules(), *getattr(self, "state_encoder", nn.Sequential())]:
            if isinstance(module, nn.Linear):  # RMB's init (the backbone keeps torchvision's)
                nn.init.kaiming_normal_(module.weight, nonlinearity="relu")
                nn.init.zeros_(module.bias)

    def forward(self, state: Tensor | None, images: Tensor | None) -> Tensor:
        features = []
        if state is not None:
            features.append(self.state_encoder(state.flatten(1)))
        if images is not None:
            batch_size = images.shape[0]
            pooled = self.backbone(images.flatten(0, 2))  # (B*T*N, F, 1, 1)
            features.append(pooled.reshape(batch_size, -1))
        out = self.head(torch.cat(features, dim=-1))
        return out.reshape(out.shape[0], self.config.chunk_size, -1)
