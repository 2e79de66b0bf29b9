"""Configuration of DP3, the 3D Diffusion Policy (``--policy.type=dp3``).

Ze et al., "3D Diffusion Policy", RSS 2024. The policy sees a sparse point cloud built from one
depth camera (back-projected with the camera's ``fovy``, cropped, farthest-point sampled to
``num_points``) and the robot state; a small PointNet encodes the cloud to 64 numbers, an MLP the
state, and a conditional 1-D U-Net denoises a ``horizon``-step action chunk with DDIM.

Defaults are DP3's (horizon 16, 2 observation steps, 8 executed actions, 100 training / 10
inference DDIM steps predicting the clean sample, PointNet (64, 128, 256) -> 64 with LayerNorm,
state MLP (64, 64), AdamW lr 1e-4, cosine schedule with 500 warm-up steps) except the U-Net,
which is smaller than DP3's (512, 1024, 2048) so that it trains on a CPU.

Depth comes in as LeRobot gives it: the dataset feature ``observation.images.<camera>_depth``
(written by ``rmb-convert to-lerobot --depth``) and, at evaluation, the same key from an RMB env
type with ``--env.depth=true``; both are float32 millimetres, (1, H, W). Images are therefore
never normalised (``VISUAL: IDENTITY``): normalising depth would break the geometry.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from lerobot.configs import NormalizationMode, PreTrainedConfig
from lerobot.configs.types import FeatureType
from lerobot.optim import AdamWConfig, DiffuserSchedulerConfig

from rmb_lerobot import lerobot_names as N

DEPTH_UNITS = {"mm": 1e-3, "m": 1.0}  # metres per depth unit
DEFAULT_CAMERA_FOVY = 45.0  # RMB's fixed UR5e cameras (front, left, right); the hand camera: 62


@dataclass
class PointCloudUnetConfig(PreTrainedConfig):
    """What DP3 and the policies built on its networks share (Flow Policy): observation windows,
    the depth -> point cloud settings, the PointNet and state encoders, the U-Net, the optimizer.
    Not a policy type itself; :class:`DP3Config` adds the DDIM settings.

    Args:
        n_obs_steps: Observation frames the policy conditions on (the current one and earlier).
        horizon: Actions denoised at once, starting at the oldest observation frame.
        n_action_steps: Actions executed per prediction, from the current step on.
        camera: The depth camera, e.g. ``"front"`` for ``observation.images.front_depth``;
            None picks the only depth feature among the inputs.
        camera_fovy: Its vertical field of view in degrees (RMB stores only this intrinsic).
            None: read from the dataset's ``meta/rmb.json`` when training starts (then saved
            with the policy), else :data:`DEFAULT_CAMERA_FOVY`.
        depth_unit: Unit of the depth feature: ``"mm"`` (what LeRobot decodes depth videos to
            and what the RMB env types deliver) or ``"m"``.
        depth_stride: Keep every k-th depth pixel on both axes before back-projection (exact:
            the intrinsics scale with it). Farthest-point sampling costs ~6 ms per 64x64 frame
            and ~0.5 s per 640x480 frame, so use e.g. 5 for RMB's 640x480 recordings.
        num_points: Points per cloud after farthest-point sampling (repeated if fewer remain).
        use_pc_color: Append the RGB of ``observation.images.<camera>`` (x, y, z, r, g, b).
        crop_min / crop_max: Box kept, in metres in the camera frame (x right, y down, z
            forward along the optical axis); the dataset has no camera poses, so the default
            crop is a depth range that drops the far background and invalid pixels.
        point_cloud_cache_size: Clouds memoised by the content of their depth (+ colour)
            frame, so later epochs skip the sampling; 0 disables.
        encoder_channels / encoder_output_dim: DP3's PointNet (per-point MLP with LayerNorm,
            max-pool, projection + LayerNorm).
        state_mlp_dims: Hidden and output sizes of the state MLP.
        down_dims, kernel_size, n_groups, diffusion_step_embed_dim, use_film_scale_modulation:
            The U-Net, LeRobot's ``DiffusionConditionalUnet1d`` (FiLM conditioning).
        do_mask_loss_for_padding: Ignore actions past an episode's end (DP3 trains on them:
            LeRobot pads with copies of the last action, which teaches holding still).
    """

    n_obs_steps: int = 2
    horizon: int = 16
    n_action_steps: int = 8

    normalization_mapping: dict[str, NormalizationMode] = field(
        default_factory=lambda: {
            "VISUAL": NormalizationMode.IDENTITY,
            "STATE": NormalizationMode.MIN_MAX,
            "ACTION": NormalizationMode.MIN_MAX,
        }
    )

    camera: str | None = None
    camera_fovy: float | None = None
    depth_unit: str = "mm"
    depth_stride: int = 1
    num_points: int = 512
    use_pc_color: bool = False
    crop_min: tuple[float, float, float] = (-1.5, -1.5, 0.1)
    crop_max: tuple[float, float, float] = (1.5, 1.5, 1.5)
    point_cloud_cache_size: int = 20000

    encoder_channels: tuple[int, ...] = (64, 128, 256)
    encoder_output_dim: int = 64
    state_mlp_dims: tuple[int, ...] = (64, 64)

    down_dims: tuple[int, ...] = (64, 128, 256)
    kernel_size: int = 5
    n_groups: int = 8
    diffusion_step_embed_dim: int = 128
    use_film_scale_modulation: bool = True
    gradient_checkpointing: bool = False
    do_mask_loss_for_padding: bool = False

    optimizer_lr: float = 1e-4
    optimizer_betas: tuple[float, float] = (0.95, 0.999)
    optimizer_eps: float = 1e-8
    optimizer_weight_decay: float = 1e-6
    scheduler_name: str = "cosine"
    scheduler_warmup_steps: int = 500

    def __post_init__(self) -> None:
        super().__post_init__()
        visual = NormalizationMode(self.normalization_mapping["VISUAL"])
        if visual is not NormalizationMode.IDENTITY:
            raise ValueError(
                f"{self.type} needs VISUAL: IDENTITY; normalising depth breaks the geometry."
            )
        if not 1 <= self.n_action_steps <= self.horizon - self.n_obs_steps + 1:
            raise ValueError(
                f"n_action_steps ({self.n_action_steps}) must be in 1..horizon - n_obs_steps + 1 "
                f"({self.horizon - self.n_obs_steps + 1})"
            )
        downsampling = 2 ** (len(self.down_dims) - 1)
        if self.horizon % downsampling:
            raise ValueError(f"horizon must be a multiple of {downsampling} (the U-Net's strides)")
        if self.depth_unit not in DEPTH_UNITS:
            raise ValueError(f"depth_unit must be one of {sorted(DEPTH_UNITS)}")
        if self.depth_stride < 1 or self.num_points < 1:
            raise ValueError("depth_stride and num_points must be >= 1")
        if any(lo > hi for lo, hi in zip(self.crop_min, self.crop_max, strict=True)):
            raise ValueError(f"crop_min {self.crop_min} must be <= crop_max {self.crop_max}")

    @property
    def depth_key(self) -> str:
        """The depth feature the point cloud comes from."""
        if self.camera is not None:
            return N.depth_image_key(self.camera)
        depth = [
            key
            for key, ft in self.input_features.items()
            if ft.type is FeatureType.VISUAL
            and key.endswith(N.DEPTH_CAMERA_SUFFIX)
            and ft.shape[0] == 1
        ]
        if len(depth) != 1:
            raise ValueError(
                f"{self.type} needs exactly one depth camera or --policy.camera; depth inputs: "
                f"{depth}. Convert with 'rmb-convert to-lerobot --depth'."
            )
        return depth[0]

    @property
    def color_key(self) -> str | None:
        """The RGB feature colouring the points (``use_pc_color``), else None."""
        if not self.use_pc_color:
            return None
        return self.depth_key.removesuffix(N.DEPTH_CAMERA_SUFFIX)

    @property
    def point_dim(self) -> int:
        return 6 if self.use_pc_color else 3

    def validate_features(self) -> None:
        if not self.robot_state_feature:
            raise ValueError(f"{self.type} needs 'observation.state'.")
        if self.action_feature is None:
            raise ValueError(f"{self.type} needs an 'action' output feature.")
        depth = self.input_features.get(self.depth_key)
        if depth is None or depth.shape[0] != 1:
            raise ValueError(f"{self.type} needs a 1-channel depth input {self.depth_key!r}.")
        if self.color_key is not None:
            rgb = self.input_features.get(self.color_key)
            if rgb is None or tuple(rgb.shape) != (3, *depth.shape[1:]):
                raise ValueError(
                    f"use_pc_color needs {self.color_key!r} (3, {depth.shape[1]}, "
                    f"{depth.shape[2]}), as large as the depth image."
                )

    def get_optimizer_preset(self) -> AdamWConfig:
        return AdamWConfig(
            lr=self.optimizer_lr,
            betas=self.optimizer_betas,
            eps=self.optimizer_eps,
            weight_decay=self.optimizer_weight_decay,
        )

    def get_scheduler_preset(self) -> DiffuserSchedulerConfig:
        return DiffuserSchedulerConfig(
            name=self.scheduler_name, num_warmup_steps=self.scheduler_warmup_steps
        )

    @property
    def observation_delta_indices(self) -> list[int]:
        return list(range(1 - self.n_obs_steps, 1))

    @property
    def action_delta_indices(self) -> list[int]:
        return list(range(1 - self.n_obs_steps, 1 - self.n_obs_steps + self.horizon))

    @property
    def reward_delta_indices(self) -> None:
        return None


@PreTrainedConfig.register_subclass("dp3")
@dataclass
class DP3Config(PointCloudUnetConfig):
    """Point cloud + state -> DDIM-denoised action chunk.

    Args (besides :class:`PointCloudUnetConfig`'s):
        num_train_timesteps, num_inference_steps, beta_*, prediction_type, clip_sample*:
            diffusers' ``DDIMScheduler``, used for both training noise and sampling, as DP3.
    """

    num_train_timesteps: int = 100
    num_inference_steps: int = 10
    beta_schedule: str = "squaredcos_cap_v2"
    beta_start: float = 1e-4
    beta_end: float = 0.02
    prediction_type: str = "sample"
    clip_sample: bool = True
    clip_sample_range: float = 1.0

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.prediction_type not in ("sample", "epsilon"):
            raise ValueError("prediction_type must be 'sample' or 'epsilon'")
