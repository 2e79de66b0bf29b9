"""ManiFlow on LeRobot's policy API: a DiT-X velocity field trained by consistency flow training.

* Observation tokens, per observation frame: per RGB camera one per cell of the last feature
  map of a ResNet-18 with GroupNorm (stride 32; as the authors' encoder without global pooling),
  or one averaged over them (``pool_image_features``), then linear; or one for the point cloud
  (the dp3 plugin's depth -> cloud pipeline and PointNet, linear); and one for the state (dp3's
  state MLP, linear); plus a learned position embedding per token.
* DiT-X (Yan et al. 2025, after DiT, Peebles & Xie 2023): each block runs self-attention over the
  action tokens, cross-attention from them to the observation tokens and an MLP, each behind a
  LayerNorm whose shift and scale, and a gate on its output, come from the condition vector
  (AdaLN-Zero: the gates start at zero, so every block starts as the identity). The condition is
  an embedding of the flow time t and of the step size dt the velocity is meant for (as the
  authors' DiT-X), plus a projection of the mean observation token.
* Training (t = 0 noise z, t = 1 the action chunk a, x_t = t a + (1 - t) z), as the authors'
  ``compute_loss``: the first ``flow_batch_ratio`` of each batch regresses v(x_t, t, dt = 0) on
  a - z with t ~ Beta(alpha, beta) (flow matching); the rest is consistency training with
  t = k / ``consistency_time_steps`` (k uniform), dt ~ U(0, 1) and s = min(t + dt, 1): the EMA
  copy's transformer (on the trained encoders' observation tokens) extrapolates from the path
  point x_s to the end, a' = x_s + (1 - s) v_ema(x_s, s, dt), and v(x_t, t, dt) regresses on
  (a' - x_t) / (1 - t). Velocities that agree with their own later predictions make the flow
  straight, so few Euler steps suffice. The loss is the flow part's mean plus the consistency
  part's mean.
* Inference: ``num_inference_steps`` Euler steps of size dt = 1 / steps from noise, with the
  EMA weights.
"""

from __future__ import annotations

import math

import torch
import torch.nn.functional as F
from lerobot.policies.pretrained import PreTrainedPolicy
from lerobot.utils.constants import ACTION, OBS_STATE
from torch import Tensor, nn
from torchvision.models.resnet import BasicBlock

from rmb_lerobot.policies_extra.dp3.modeling_dp3 import PointNetEncoder, mlp
from rmb_lerobot.policies_extra.dp3.point_cloud import DepthPointClouds, resolve_camera
from rmb_lerobot.policies_extra.ema import EmaWeights
from rmb_lerobot.policies_extra.flow_policy.modeling_flow_policy import per_sample
from rmb_lerobot.policies_extra.observation_history import ObservationHistory

from .configuration_maniflow import ManiFlowConfig

CLOUD = "cloud"  # key of the (B, T, P, C) point clouds among the model inputs


def sinusoidal_embedding(t: Tensor, dim: int) -> Tensor:
    """(B,) scalars -> (B, dim) sin/cos features at geometric frequencies (as DiT)."""
    half = dim // 2
    freqs = torch.exp(-math.log(10000.0) * torch.arange(half, device=t.device) / half)
    angles = t.float()[:, None] * freqs[None]
    return torch.cat([angles.sin(), angles.cos()], dim=-1)


class ResNet18GroupNorm(nn.Module):
    """ResNet-18 (torchvision's BasicBlock, stages of 2) with GroupNorm instead of BatchNorm:
    (N, 3, H, W) in [0, 1] -> (N, h * w, 8 * width) features of the last stage's h x w cells
    (stride 32), or (N, 1, 8 * width) averaged over them (``pool``). ``width`` 64 is ResNet-18
    (11.2 M parameters); GroupNorm keeps small, correlated robot batches stable."""

    STRIDED_LAYERS = 5  # stem conv, max-pool and the first conv of stages 2-4 halve the size

    def __init__(self, width: int, groupnorm_channels: int, pool: bool = False):
        super().__init__()
        self.pool = pool

        def norm(channels: int) -> nn.GroupNorm:
            return nn.GroupNorm(channels // groupnorm_channels, channels)

        self.stem = nn.Sequential(
            nn.Conv2d(3, width, kernel_size=7, stride=2, padding=3, bias=False),
            norm(width),
            nn.ReLU(inplace=True),
            nn.MaxPool2d(kernel_size=3, stride=2, padding=1),
        )
        stages, inplanes = [], width
        for i in range(4):
            planes, stride = width * 2**i, 1 if i == 0 else 2
            downsample = None
            if stride != 1 or inplanes != planes:
                downsample = nn.Sequential(
                    nn.Conv2d(inplanes, planes, kernel_size=1, stride=stride, bias=False),
                    norm(planes),
                )
            stages += [
                BasicBlock(inplanes, planes, stride, downsample, norm_layer=norm),
                BasicBlock(planes, planes, norm_layer=norm),
            ]
            inplanes = planes
        self.stages = nn.Sequential(*stages)
        self.out_dim = inplanes

    def num_tokens(self, height: int, width: int) -> int:
        """Feature cells of an image: each strided layer (kernel 2p + 1, padding p) maps a size
        n to (n - 1) // 2 + 1."""
        if self.pool:
            return 1
        for _ in range(self.STRIDED_LAYERS):
            height, width = (height - 1) // 2 + 1, (width - 1) // 2 + 1
        return height * width

    def forward(self, images: Tensor) -> Tensor:
        features = self.stages(self.stem(images)).flatten(start_dim=2).transpose(1, 2)
        return features.mean(dim=1, keepdim=True) if self.pool else features


def modulate(x: Tensor, shift: Tensor, scale: Tensor) -> Tensor:
    """AdaLN: (B, N, D) normalised tokens shifted and scaled by (B, D) condition terms."""
    return x * (1 + scale[:, None]) + shift[:, None]


class DiTXBlock(nn.Module):
    """Self-attention, cross-attention to the observation tokens and an MLP, each AdaLN-Zero
    modulated by the condition vector."""

    def __init__(self, width: int, heads: int, mlp_ratio: float, dropout: float):
        super().__init__()
        self.norms = nn.ModuleList(
            nn.LayerNorm(width, elementwise_affine=False, eps=1e-6) for _ in range(3)
        )
        self.self_attn = nn.MultiheadAttention(width, heads, dropout=dropout, batch_first=True)
        self.cross_attn = nn.MultiheadAttention(width, heads, dropout=dropout, batch_first=True)
        hidden = int(width * mlp_ratio)
        self.mlp = nn.Sequential(
            nn.Linear(width, hidden), nn.GELU(approximate="tanh"), nn.Dropout(dropout),
            nn.Linear(hidden, width),
        )  # fmt: skip
        self.adaln = nn.Sequential(nn.SiLU(), nn.Linear(width, 9 * width))
        nn.init.zeros_(self.adaln[-1].weight)
        nn.init.zeros_(self.adaln[-1].bias)

    def forward(self, x: Tensor, obs: Tensor, cond: Tensor) -> Tensor:
        mods = self.adaln(cond).chunk(9, dim=-1)
        h = modulate(self.norms[0](x), mods[0], mods[1])
        x = x + mods[2][:, None] * self.self_attn(h, h, h, need_weights=False)[0]
        h = modulate(self.norms[1](x), mods[3], mods[4])
        x = x + mods[5][:, None] * self.cross_attn(h, obs, obs, need_weights=False)[0]
        h = modulate(self.norms[2](x), mods[6], mods[7])
        return x + mods[8][:, None] * self.mlp(h)


class ManiFlowModel(nn.Module):
    """Observation encoders + DiT-X: a velocity field over action chunks."""

    def __init__(self, config: ManiFlowConfig):
        super().__init__()
        self.config = config
        width, n_obs = config.n_emb, config.n_obs_steps
        action_dim = config.action_feature.shape[0]
        state_dim = config.robot_state_feature.shape[0]

        self.state_encoder = nn.Sequential(
            mlp(state_dim, tuple(config.state_mlp_dims)),
            nn.Linear(config.state_mlp_dims[-1], width),
        )
        if config.obs_encoder == "image":
            self.image_keys = config.image_keys
            self.image_encoder = ResNet18GroupNorm(
                config.resnet_width, config.groupnorm_channels, pool=config.pool_image_features
            )
            self.image_projection = nn.Linear(self.image_encoder.out_dim, width)
            tokens_per_frame = 1 + sum(
                self.image_encoder.num_tokens(*config.input_features[key].shape[1:])
                for key in self.image_keys
            )
        else:
            self.image_keys = ()
            self.point_encoder = nn.Sequential(
                PointNetEncoder(
                    config.point_dim, tuple(config.encoder_channels), config.encoder_output_dim
                ),
                nn.Linear(config.encoder_output_dim, width),
            )
            tokens_per_frame = 2
        self.obs_pos = nn.Parameter(torch.zeros(1, n_obs * tokens_per_frame, width))

        self.action_in = nn.Linear(action_dim, width)
        self.action_pos = nn.Parameter(torch.zeros(1, config.horizon, width))
        self.time_mlp = nn.Sequential(  # (t, dt) sinusoidal embeddings -> condition
            nn.Linear(2 * width, width), nn.SiLU(), nn.Linear(width, width)
        )
        self.obs_cond = nn.Linear(width, width)
        self.blocks = nn.ModuleList(
            DiTXBlock(width, config.n_head, config.mlp_ratio, config.dropout)
            for _ in range(config.n_layer)
        )
        self.final_norm = nn.LayerNorm(width, elementwise_affine=False, eps=1e-6)
        self.final_adaln = nn.Sequential(nn.SiLU(), nn.Linear(width, 2 * width))
        self.action_out = nn.Linear(width, action_dim)
        nn.init.normal_(self.obs_pos, std=0.02)
        nn.init.normal_(self.action_pos, std=0.02)
        for layer in (self.final_adaln[-1], self.action_out):
            nn.init.zeros_(layer.weight)
            nn.init.zeros_(layer.bias)

    def observation_tokens(self, obs: dict[str, Tensor]) -> Tensor:
        """Model inputs (state (B, T, S) and images (B, T, 3, H, W) or cloud (B, T, P, C)) ->
        (B, T * tokens_per_frame, n_emb) tokens: per frame the state's, then each camera's
        feature cells (or the cloud's)."""
        state = obs[OBS_STATE]
        batch, steps = state.shape[:2]
        per_frame = [self.state_encoder(state).unsqueeze(2)]
        if self.image_keys:
            for key in self.image_keys:
                features = self.image_projection(self.image_encoder(obs[key].flatten(0, 1)))
                per_frame.append(features.view(batch, steps, *features.shape[1:]))
        else:
            per_frame.append(self.point_encoder(obs[CLOUD]).unsqueeze(2))
        tokens = torch.cat(per_frame, dim=2).flatten(1, 2)
        if tokens.shape[1] != self.obs_pos.shape[1]:
            raise ValueError(
                f"{tokens.shape[1]} observation tokens, the model was built for "
                f"{self.obs_pos.shape[1]}: images must have the sizes of the input features"
            )
        return tokens + self.obs_pos

    def velocity(self, x: Tensor, t: Tensor, dt: Tensor, obs_tokens: Tensor) -> Tensor:
        """Velocity (B, horizon, A) at action chunks ``x``, (B,) flow times ``t``, for steps of
        (B,) sizes ``dt`` (0: the instantaneous velocity)."""
        cfg = self.config
        times = [sinusoidal_embedding(v * cfg.time_scale, cfg.n_emb) for v in (t, dt)]
        cond = self.time_mlp(torch.cat(times, dim=-1))
        cond = cond + self.obs_cond(obs_tokens.mean(dim=1))
        h = self.action_in(x) + self.action_pos
        for block in self.blocks:
            h = block(h, obs_tokens, cond)
        shift, scale = self.final_adaln(cond).chunk(2, dim=-1)
        return self.action_out(modulate(self.final_norm(h), shift, scale))

    def compute_loss(
        self,
        obs: dict[str, Tensor],
        actions: Tensor,
        ema: ManiFlowModel | None,
        is_pad: Tensor | None = None,
    ) -> tuple[Tensor, dict[str, float]]:
        """Flow-matching + consistency loss of a batch; ``ema`` gives the consistency targets
        (the model itself, without gradient, if None)."""
        cfg = self.config
        batch, device = actions.shape[0], actions.device
        n_flow = int(batch * cfg.flow_batch_ratio)
        n_cons = batch - n_flow
        noise = torch.randn_like(actions)
        straight = actions - noise  # velocity of the straight noise -> action path

        t_flow = torch.distributions.Beta(cfg.flow_t_alpha, cfg.flow_t_beta).sample((n_flow,))
        steps = cfg.consistency_time_steps
        t_cons = torch.randint(0, steps, (n_cons,)).float() / steps
        dt_cons = torch.rand(n_cons)
        t = torch.cat([t_flow, t_cons]).to(device)
        dt = torch.cat([torch.zeros(n_flow), dt_cons]).to(device)

        tokens = self.observation_tokens(obs)
        x_t = per_sample(t) * actions + (1.0 - per_sample(t)) * noise
        pred = self.velocity(x_t, t, dt, tokens)

        target = straight.clone()
        if n_cons:
            with torch.no_grad():
                teacher = ema if ema is not None else self
                c = slice(n_flow, batch)
                s = (t[c] + dt[c]).clamp(max=1.0)
                x_s = per_sample(s) * actions[c] + (1.0 - per_sample(s)) * noise[c]
                v_s = teacher.velocity(x_s, s, dt[c], tokens[c].detach())
                end = x_s + per_sample(1.0 - s) * v_s
                target[c] = (end - x_t[c]) / per_sample(1.0 - t[c])
        loss = F.mse_loss(pred, target, reduction="none")
        if cfg.do_mask_loss_for_padding and is_pad is not None:
            valid = (~is_pad).unsqueeze(-1).expand_as(loss)
            loss = loss * valid / valid.float().mean().clamp_min(1e-6)
        per_row = loss.mean(dim=(1, 2))
        flow = per_row[:n_flow].mean() if n_flow else per_row.new_zeros(())
        consistency = per_row[n_flow:].mean() if n_cons else per_row.new_zeros(())
        info = {"flow_loss": flow.item(), "consistency_loss": consistency.item()}
        return flow + consistency, info

    def generate_actions(self, obs: dict[str, Tensor], noise: Tensor | None = None) -> Tensor:
        """Euler steps from noise to a chunk; its ``n_action_steps`` from the current frame."""
        cfg = self.config
        state = obs[OBS_STATE]
        shape = (state.shape[0], cfg.horizon, cfg.action_feature.shape[0])
        x = noise if noise is not None else torch.randn(shape, device=state.device)
        tokens = self.observation_tokens(obs)
        steps = cfg.num_inference_steps
        dt = torch.full((shape[0],), 1.0 / steps, device=x.device)
        for i in range(steps):
            t = torch.full((shape[0],), i / steps, device=x.device)
            x = x + self.velocity(x, t, dt, tokens) / steps
        start = cfg.n_obs_steps - 1
        return x[:, start : start + cfg.n_action_steps]


def _rows(obs: dict[str, Tensor], rows: slice) -> dict[str, Tensor]:
    return {k: v[rows] for k, v in obs.items()}


class ManiFlowPolicy(EmaWeights, ObservationHistory, PreTrainedPolicy):
    """Images or point cloud + state -> chunk of actions, ``n_action_steps`` executed.

    LeRobot's factory finds it by convention: ``ManiFlowConfig`` -> ``ManiFlowPolicy`` in the
    sibling ``modeling_`` module (so, unlike flow_policy, no alias is needed).
    """

    config_class = ManiFlowConfig
    name = "maniflow"
    missing_input_hint = (
        "RMB env types deliver cameras with --env.cameras=[...], depth with --env.depth=true"
    )

    def __init__(self, config: ManiFlowConfig, dataset_meta=None, **kwargs):
        """``dataset_meta`` (from ``make_policy`` when training) supplies a depth camera's fovy."""
        super().__init__(config)
        config.validate_features()
        self.config = config
        self.point_clouds: DepthPointClouds | None = None
        if config.obs_encoder == "pointcloud":
            resolve_camera(config, dataset_meta)
            self.point_clouds = DepthPointClouds(config)
        self.model = ManiFlowModel(config)
        self.init_ema()  # the consistency targets and inference use it: always on
        self.reset()

    @property
    def observation_keys(self) -> tuple[str, ...]:
        cfg = self.config
        if cfg.obs_encoder == "image":
            return (OBS_STATE, *cfg.image_keys)
        keys = (OBS_STATE, cfg.depth_key, cfg.color_key)
        return tuple(k for k in keys if k is not None)

    def model_inputs(self, batch: dict[str, Tensor]) -> dict[str, Tensor]:
        """Observation windows (B, T, ...) -> what the model encodes (depth becomes a cloud)."""
        self._check_inputs(batch)
        cfg = self.config
        if self.point_clouds is None:
            return {k: batch[k] for k in self.observation_keys}
        rgb = batch[cfg.color_key] if cfg.color_key is not None else None
        return {OBS_STATE: batch[OBS_STATE], CLOUD: self.point_clouds(batch[cfg.depth_key], rgb)}

    def sample_chunk(self, window: dict[str, Tensor], noise: Tensor | None) -> Tensor:
        """Actions from the EMA weights."""
        return self.ema_model.generate_actions(self.model_inputs(window), noise=noise)

    def forward(self, batch: dict[str, Tensor]) -> tuple[Tensor, dict]:
        """Loss of a batch of windows: observations (B, n_obs_steps, ...), ``action``
        (B, horizon, A) and ``action_is_pad`` (B, horizon)."""
        batch = self.as_windows(batch)
        return self.model.compute_loss(
            self.model_inputs(batch), batch[ACTION], self.ema_model, batch.get(f"{ACTION}_is_pad")
        )
