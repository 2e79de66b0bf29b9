"""Flow Policy on LeRobot's policy API: DP3's networks, consistency flow matching.

Everything up to the U-Net is the dp3 plugin's (:class:`DP3Policy` handles the observation
history, the depth -> point cloud step and the action queue; :class:`PointCloudUnet` holds the
PointNet, the state MLP and the U-Net). What differs is the generative process:

* Training (multi-segment consistency flow matching, Yang et al. 2024, as FlowPolicy uses it):
  x_t = t a + (1 - t) z on the straight path from noise z to the action chunk a. For t and
  r = min(t + delta, 1) the U-Net's velocities v_t, v_r extrapolate both points to the end s of
  t's segment, f_t = x_t + (s - t) v_t and f_r = x_r + (s - r) v_r (the true x_s once r reaches
  ``boundary``); the loss is |f_t - f_r|^2 + alpha |v_t - v_r|^2, the velocity term only where
  t is more than delta before s. Gradients flow through both branches, as in FlowPolicy.
* Inference: ``num_inference_steps`` Euler steps of that velocity from noise, starting at
  t = eps; one step by default.
"""

from __future__ import annotations

import torch
from torch import Tensor

from rmb_lerobot.policies_extra.dp3.modeling_dp3 import DP3Policy, PointCloudUnet

from .configuration_flow_policy import FlowPolicyConfig


class ConsistencyFlowModel(PointCloudUnet):
    """DP3's encoders and U-Net as a velocity field, trained for consistency along segments."""

    config: FlowPolicyConfig

    def velocity(self, x: Tensor, t: Tensor, cond: Tensor) -> Tensor:
        """U-Net velocity at (B, horizon, A) points ``x`` and (B,) flow times ``t``."""
        return self.unet(x, t * self.config.timestep_scale, global_cond=cond)

    def compute_loss(
        self, state: Tensor, cloud: Tensor, actions: Tensor, is_pad: Tensor | None = None
    ) -> Tensor:
        cfg = self.config
        cond = self.global_condition(state, cloud)
        noise = torch.randn_like(actions)
        batch = actions.shape[0]

        def on_path(time: Tensor) -> Tensor:
            return per_sample(time) * actions + (1.0 - per_sample(time)) * noise

        t = torch.rand(batch, device=actions.device) * (1.0 - cfg.eps) + cfg.eps
        r = (t + cfg.delta).clamp(max=1.0)
        edges = torch.linspace(0.0, 1.0, cfg.num_segments + 1, device=actions.device)
        seg_end = edges[torch.searchsorted(edges, t, side="left").clamp(min=1)]

        x_t, x_r = on_path(t), on_path(r)
        v_t, v_r = self.velocity(x_t, t, cond), self.velocity(x_r, r, cond)
        f_t = x_t + per_sample(seg_end - t) * v_t
        f_r = torch.where(
            per_sample(r) < cfg.boundary, x_r + per_sample(seg_end - r) * v_r, on_path(seg_end)
        )
        # FlowPolicy masks the velocity term with t (not r) < boundary; same for boundary 1.
        use_v = (t < cfg.boundary) & (seg_end - t > 1.01 * cfg.delta)
        loss = (f_t - f_r).square() + cfg.alpha * per_sample(use_v) * (v_t - v_r).square()
        return self.reduce_loss(loss, is_pad)

    def generate_actions(self, state: Tensor, cloud: Tensor, noise: Tensor | None = None) -> Tensor:
        """Euler steps of the velocity from noise; the ``n_action_steps`` from the current frame."""
        cfg = self.config
        cond = self.global_condition(state, cloud)
        shape = (state.shape[0], cfg.horizon, cfg.action_feature.shape[0])
        x = noise if noise is not None else torch.randn(shape, device=state.device)
        steps = cfg.num_inference_steps
        for i in range(steps):
            t = torch.full((shape[0],), i / steps * (1.0 - cfg.eps) + cfg.eps, device=x.device)
            x = x + self.velocity(x, t, cond) / steps
        return self.executed(x)


def per_sample(values: Tensor) -> Tensor:
    """(B,) -> (B, 1, 1), to scale (B, horizon, A) chunks sample by sample."""
    return values.to(torch.float32).view(-1, 1, 1)


class FlowPolicy(DP3Policy):
    """Point cloud + state -> chunk of actions from one flow step, ``n_action_steps`` executed."""

    config_class = FlowPolicyConfig
    name = "flow_policy"

    def make_model(self, config: FlowPolicyConfig) -> ConsistencyFlowModel:
        return ConsistencyFlowModel(config)


# LeRobot's factory finds the policy class of a config ``<Name>Config`` as ``<Name>Policy``.
FlowPolicyPolicy = FlowPolicy
