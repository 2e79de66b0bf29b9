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

import math
from dataclasses import dataclass, field

from lerobot.configs import NormalizationMode, PreTrainedConfig
from lerobot.configs.types import FeatureType
from lerobot.optim import AdamWConfig, DiffuserSchedulerConfig

from rmb_lerobot import lerobot_names as N
from rmb_lerobot.pointcloud import checked_camera_pose

DEPTH_UNITS = {"mm": 1e-3, "m": 1.0}  # metres per depth unit
DEFAULT_CAMERA_FOVY = 45.0  # RMB's fixed UR5e cameras (front, left, right); the hand camera: 62
CROP_FRAMES = ("auto", "camera", "world")
# Default crop boxes (min, max) in metres per frame. Camera frame (x right, y down, z forward):
# a depth range that drops invalid pixels and the far background. World frame (z up): the UR5e
# MuJoCo tables' workspace above the table top (RMB_TABLE in rmb_lerobot/envs/workspace.py: top
# surface z = 0.815 m, x in +-0.275, y in +-0.5, the same table in every UR5e task), from 1.5 cm
# above the top (drops the table: its back-projected pixels lie within ~7 mm of it at 64x64),
# back to x = -0.8 so that the arm on its stand at x = -0.605 stays, up to 1.6 m.
DEFAULT_CROP = {
    "camera": ((-1.5, -1.5, 0.1), (1.5, 1.5, 1.5)),
    "world": ((-0.8, -0.5, 0.83), (0.35, 0.5, 1.6)),
}


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
        camera_pose: The camera's 4x4 world-from-camera transform (metres; camera axes x right,
            y down, z forward), as rmb-collect records it for cameras fixed to the world
            (``<camera>_depth_image_pose``). None: read from the dataset's ``meta/rmb.json``
            when training starts (then saved with the policy); stays None for data recorded
            without it. Checked against the dataset when set.
        crop_frame: Where the cloud is cropped and which frame the PointNet sees: ``"camera"``
            (points in the camera frame), ``"world"`` (points moved to the world frame with
            ``camera_pose``, cropped there, as DP3 and RMB do; needs the pose) or ``"auto"``
            (world when the pose is known, else camera).
        crop_min: Lower corner of the box kept, in metres in the crop frame. None: that
            frame's default
            (:data:`DEFAULT_CROP`): camera frame (-1.5, -1.5, 0.1)..(1.5, 1.5, 1.5), a depth
            range that drops the far background and invalid pixels; world frame
            (-0.8, -0.5, 0.83)..(0.35, 0.5, 1.6), the UR5e table's workspace above its top
            (z = 0.815 m), so the table surface is dropped and the objects and the arm stay.
        crop_max: Upper corner of that box (None: the frame's default, as ``crop_min``).
        point_cloud_cache_size: Clouds memoised by the content of their depth (+ colour)
            frame, so later epochs skip the sampling; 0 disables.
        encoder_channels: Widths of DP3's PointNet per-point MLP (with LayerNorm), which is
            max-pooled, projected and normalised.
        encoder_output_dim: Width of the PointNet's output (the projection).
        state_mlp_dims: Hidden and output sizes of the state MLP.
        down_dims: Channels of the U-Net's levels (LeRobot's ``DiffusionConditionalUnet1d``,
            FiLM conditioning).
        kernel_size: The U-Net's convolution kernel size.
        n_groups: Groups of the U-Net's GroupNorm.
        diffusion_step_embed_dim: Width of the U-Net's diffusion-step embedding.
        use_film_scale_modulation: FiLM with scale and bias (else bias only).
        do_mask_loss_for_padding: Ignore actions past an episode's end (DP3 trains on them:
            LeRobot pads with copies of the last action, which teaches holding still).
        use_ema: Predict with an exponential moving average of the weights, updated after each
            optimizer step (LeRobot's train loop calls ``policy.update()``) and saved with the
            policy; DP3 and RMB's ``TrainDiffusionPolicy3d`` sample from it (on by default).
        ema_power: The EMA's warm-up, decay = 1 - (1 + step) ** -power (diffusion_policy's
            ``EMAModel`` as RMB configures it: 0.75).
        ema_max_decay: The cap on that decay (0.9999).
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
    camera_pose: list[list[float]] | None = None
    crop_frame: str = "auto"
    crop_min: tuple[float, float, float] | None = None
    crop_max: tuple[float, float, float] | None = None
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

    use_ema: bool = True
    ema_power: float = 0.75
    ema_max_decay: float = 0.9999

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
        if self.crop_frame not in CROP_FRAMES:
            raise ValueError(f"crop_frame must be one of {CROP_FRAMES}, got {self.crop_frame!r}")
        for name in ("crop_min", "crop_max"):
            value = getattr(self, name)
            if value is not None:
                if len(value) != 3 or not all(math.isfinite(float(v)) for v in value):
                    raise ValueError(f"{name} must be 3 finite numbers (x, y, z), got {value!r}")
                setattr(self, name, tuple(float(v) for v in value))
        if self.camera_pose is not None:
            self.camera_pose = checked_camera_pose(self.camera_pose, "camera_pose")
        if not (self.crop_frame == "world" and self.camera_pose is None):
            # The box of the frame known now; a pose may still come from the dataset
            # (resolve_camera_pose), and the point-cloud builder asks for the box again.
            self.crop_box()
        if not 0.0 <= self.ema_max_decay < 1.0:
            raise ValueError(f"ema_max_decay must be in [0, 1), got {self.ema_max_decay}")

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
    def resolved_crop_frame(self) -> str:
        """``"camera"`` or ``"world"``: ``crop_frame`` with ``"auto"`` decided by the pose."""
        if self.crop_frame == "auto":
            return "camera" if self.camera_pose is None else "world"
        return self.crop_frame

    def crop_box(self) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        """``(crop_min, crop_max)`` in :attr:`resolved_crop_frame`, defaults filled in."""
        frame = self.resolved_crop_frame
        if frame == "world" and self.camera_pose is None:
            raise ValueError(
                f"crop_frame={self.crop_frame!r} needs camera_pose (the camera's 4x4 world pose), "
                "which the dataset does not record: set --policy.camera_pose or use "
                "crop_frame='camera'"
            )
        default_min, default_max = DEFAULT_CROP[frame]
        low = default_min if self.crop_min is None else tuple(self.crop_min)
        high = default_max if self.crop_max is None else tuple(self.crop_max)
        if any(lo > hi for lo, hi in zip(low, high, strict=True)):
            raise ValueError(f"crop_min {low} must be <= crop_max {high} ({frame} frame)")
        return low, high

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
