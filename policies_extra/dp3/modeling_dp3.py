"""3D Diffusion Policy (DP3) on LeRobot's policy API.

Architecture as Ze et al. (RSS 2024) / the DP3 reference code: per observation frame, a
PointNet (shared per-point MLP with LayerNorm, max-pool over points, projection to 64 + LayerNorm)
encodes the point cloud and an MLP the state; the features of the ``n_obs_steps`` frames are
the global condition (FiLM) of a 1-D convolutional U-Net that denoises the action chunk, trained
and sampled with diffusers' DDIM scheduler. The U-Net is LeRobot's ``DiffusionConditionalUnet1d``
(the Chi et al. network DP3 builds on), fed with this policy's config.

Point clouds are built from the depth feature inside the policy (see :mod:`.point_cloud`), so
training batches, ``select_action`` and a reloaded checkpoint all start from the same depth
input; LeRobot's processors only normalise state and action.
"""

from __future__ import annotations

import itertools

import torch
import torch.nn.functional as F
from diffusers.schedulers.scheduling_ddim import DDIMScheduler
from lerobot.policies.diffusion.modeling_diffusion import DiffusionConditionalUnet1d
from lerobot.policies.pretrained import PreTrainedPolicy
from lerobot.utils.constants import ACTION, OBS_STATE
from torch import Tensor, nn

from rmb_lerobot.policies_extra.ema import EmaWeights
from rmb_lerobot.policies_extra.observation_history import ObservationHistory

from .configuration_dp3 import DP3Config, PointCloudUnetConfig
from .point_cloud import DepthPointClouds, resolve_camera

POINT_CLOUD = "observation.point_cloud"  # (B, n_obs_steps, num_points, 3 or 6), made here


class DP3Policy(EmaWeights, ObservationHistory, PreTrainedPolicy):
    """Point cloud + state -> chunk of actions, ``n_action_steps`` executed per prediction."""

    config_class = DP3Config
    name = "dp3"

    def __init__(self, config: PointCloudUnetConfig, dataset_meta=None, **kwargs):
        """``dataset_meta`` (from ``make_policy`` when training) supplies the camera's fovy."""
        super().__init__(config)
        config.validate_features()
        resolve_camera(config, dataset_meta)
        self.config = config
        self.point_clouds = DepthPointClouds(config)
        self.model = self.make_model(config)
        self.ema_model = None
        if config.use_ema:
            self.init_ema()
        self.reset()

    def make_model(self, config: PointCloudUnetConfig) -> PointCloudUnet:
        """The networks with their generative process (policies built on DP3 swap it)."""
        return DP3Model(config)

    @property
    def observation_keys(self) -> tuple[str, ...]:
        """The inputs DP3 reads: state, depth and (``use_pc_color``) the camera's RGB."""
        keys = (OBS_STATE, self.config.depth_key, self.config.color_key)
        return tuple(k for k in keys if k is not None)

    def model_inputs(self, batch: dict[str, Tensor]) -> tuple[Tensor, Tensor]:
        """State (B, T, S) and point clouds (B, T, P, C) of observation windows (B, T, ...)."""
        self._check_inputs(batch)
        cfg = self.config
        rgb = batch[cfg.color_key] if cfg.color_key is not None else None
        return batch[OBS_STATE], self.point_clouds(batch[cfg.depth_key], rgb)

    def sampling_model(self) -> PointCloudUnet:
        """The network that predicts actions: the EMA of :attr:`model`'s weights (``use_ema``)."""
        return self.ema_model if self.ema_model is not None else self.model

    def sample_chunk(self, window: dict[str, Tensor], noise: Tensor | None) -> Tensor:
        return self.sampling_model().generate_actions(*self.model_inputs(window), noise=noise)

    def forward(self, batch: dict[str, Tensor]) -> tuple[Tensor, dict]:
        """Denoising loss of a batch of windows: observations (B, n_obs_steps, ...), ``action``
        (B, horizon, A) and ``action_is_pad`` (B, horizon)."""
        batch = self.as_windows(batch)
        state, cloud = self.model_inputs(batch)
        loss = self.model.compute_loss(state, cloud, batch[ACTION], batch.get(f"{ACTION}_is_pad"))
        return loss, {}


class PointNetEncoder(nn.Module):
    """DP3's PointNetEncoderXYZ: (..., P, C) points -> (..., out_dim) feature."""

    def __init__(self, in_channels: int, channels: tuple[int, ...], out_dim: int):
        super().__init__()
        layers: list[nn.Module] = []
        for c_in, c_out in itertools.pairwise((in_channels, *channels)):
            layers += [nn.Linear(c_in, c_out), nn.LayerNorm(c_out), nn.ReLU()]
        self.mlp = nn.Sequential(*layers)
        self.projection = nn.Sequential(nn.Linear(channels[-1], out_dim), nn.LayerNorm(out_dim))

    def forward(self, points: Tensor) -> Tensor:
        return self.projection(self.mlp(points).amax(dim=-2))


def mlp(in_dim: int, dims: tuple[int, ...]) -> nn.Sequential:
    """Linear layers with ReLU between them (none after the last), as DP3's state MLP."""
    layers: list[nn.Module] = []
    for c_in, c_out in itertools.pairwise((in_dim, *dims)):
        layers += [nn.Linear(c_in, c_out), nn.ReLU()]
    return nn.Sequential(*layers[:-1])


class PointCloudUnet(nn.Module):
    """DP3's networks without a generative process: the observation encoders (the global
    condition) and the conditional U-Net; subclasses add training loss and sampling."""

    def __init__(self, config: PointCloudUnetConfig):
        super().__init__()
        self.config = config
        self.point_encoder = PointNetEncoder(
            config.point_dim, tuple(config.encoder_channels), config.encoder_output_dim
        )
        self.state_encoder = mlp(config.robot_state_feature.shape[0], tuple(config.state_mlp_dims))
        cond_dim = (config.encoder_output_dim + config.state_mlp_dims[-1]) * config.n_obs_steps
        self.unet = DiffusionConditionalUnet1d(config, global_cond_dim=cond_dim)

    def global_condition(self, state: Tensor, cloud: Tensor) -> Tensor:
        """(B, T, S) states and (B, T, P, C) clouds -> (B, T * (64 + state feature))."""
        features = torch.cat([self.point_encoder(cloud), self.state_encoder(state)], dim=-1)
        return features.flatten(start_dim=1)

    def reduce_loss(self, loss: Tensor, is_pad: Tensor | None) -> Tensor:
        """Mean of an elementwise (B, horizon, A) loss, over real actions only if configured."""
        if self.config.do_mask_loss_for_padding and is_pad is not None:
            valid = (~is_pad).unsqueeze(-1).expand_as(loss)
            return (loss * valid).sum() / valid.sum().clamp_min(1)
        return loss.mean()

    def executed(self, chunk: Tensor) -> Tensor:
        """The ``n_action_steps`` of a (B, horizon, A) chunk from the current frame on."""
        start = self.config.n_obs_steps - 1
        return chunk[:, start : start + self.config.n_action_steps]

    def compute_loss(
        self, state: Tensor, cloud: Tensor, actions: Tensor, is_pad: Tensor | None = None
    ) -> Tensor:
        raise NotImplementedError

    def generate_actions(self, state: Tensor, cloud: Tensor, noise: Tensor | None = None) -> Tensor:
        raise NotImplementedError


class DP3Model(PointCloudUnet):
    """Observation encoders, the conditional U-Net and the DDIM noise scheduler."""

    def __init__(self, config: DP3Config):
        super().__init__(config)
        self.noise_scheduler = DDIMScheduler(
            num_train_timesteps=config.num_train_timesteps,
            beta_start=config.beta_start,
            beta_end=config.beta_end,
            beta_schedule=config.beta_schedule,
            clip_sample=config.clip_sample,
            clip_sample_range=config.clip_sample_range,
            set_alpha_to_one=True,
            steps_offset=0,
            prediction_type=config.prediction_type,
        )

    def compute_loss(
        self, state: Tensor, cloud: Tensor, actions: Tensor, is_pad: Tensor | None = None
    ) -> Tensor:
        cond = self.global_condition(state, cloud)
        noise = torch.randn_like(actions)
        timesteps = torch.randint(
            0, self.config.num_train_timesteps, (actions.shape[0],), device=actions.device
        )
        noisy = self.noise_scheduler.add_noise(actions, noise, timesteps)
        pred = self.unet(noisy, timesteps, global_cond=cond)
        target = actions if self.config.prediction_type == "sample" else noise
        return self.reduce_loss(F.mse_loss(pred, target, reduction="none"), is_pad)

    def generate_actions(self, state: Tensor, cloud: Tensor, noise: Tensor | None = None) -> Tensor:
        """DDIM sampling of a horizon; returns its ``n_action_steps`` from the current frame."""
        cfg = self.config
        cond = self.global_condition(state, cloud)
        shape = (state.shape[0], cfg.horizon, cfg.action_feature.shape[0])
        sample = noise if noise is not None else torch.randn(shape, device=state.device)
        self.noise_scheduler.set_timesteps(cfg.num_inference_steps)
        for t in self.noise_scheduler.timesteps:
            steps = torch.full((shape[0],), int(t), dtype=torch.long, device=state.device)
            output = self.unet(sample, steps, global_cond=cond)
            sample = self.noise_scheduler.step(output, t, sample).prev_sample
        return self.executed(sample)
