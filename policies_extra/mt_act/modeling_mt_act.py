"""MT-ACT on LeRobot's policy API: LeRobot's ACT, conditioned on the task sentence.

:class:`MTACTPolicy` is :class:`ACTPolicy` (same VAE, transformer, losses, action queue and
optimizer groups); after ACT builds its network, two kinds of wrappers are put around parts of it,
so ACT's own ``forward`` runs unchanged:

* FiLM: ResNet stages 1-3 (``model.backbone.layer1..3``) become :class:`FiLMStage`, whose output
  is scaled and shifted per channel by linear maps of the sentence embedding
  (``(1 + gamma) * x + beta``, zero-initialised, so an ImageNet backbone starts unchanged).
* Extra token: ACT's transformer encoder becomes :class:`TextTokenEncoder`, which prepends the
  projected embedding as one more token; the decoder (:class:`TextTokenDecoder`) gets a zero
  positional embedding for it, so it cross-attends to it like any other encoder output.

The embedding of the batch's task strings (``batch["task"]``: the dataset's task during training,
the env's ``task_description`` in ``lerobot-eval``) is set on a shared :class:`TextContext` for
the duration of one ACT forward (scaled to unit RMS per entry, see :meth:`task_embedding`).
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from typing import Any

import torch
from lerobot.policies.act.modeling_act import ACT, ACTDecoder, ACTEncoder, ACTPolicy
from lerobot.utils.constants import OBS_ENV_STATE, OBS_STATE
from torch import Tensor, nn

from .configuration_mt_act import FILM_STAGES, MTACTConfig
from .text_encoder import TextEncoder

TASK = "task"  # LeRobot's batch key for the task string(s)


class TextContext:
    """The current batch's (B, text_dim) sentence embeddings, shared by the wrappers."""

    def __init__(self) -> None:
        self.embedding: Tensor | None = None

    def current(self) -> Tensor:
        if self.embedding is None:
            raise RuntimeError("MT-ACT's network ran without a task embedding; call the policy")
        return self.embedding


class FiLMStage(nn.Module):
    """A ResNet stage whose output is modulated per channel by the sentence embedding."""

    def __init__(self, stage: nn.Module, channels: int, text_dim: int, context: TextContext):
        super().__init__()
        self.stage = stage
        self.film = nn.Linear(text_dim, 2 * channels)
        nn.init.zeros_(self.film.weight)
        nn.init.zeros_(self.film.bias)
        self.context = context

    def forward(self, x: Tensor) -> Tensor:
        x = self.stage(x)
        gamma, beta = self.film(self.context.current()).chunk(2, dim=-1)
        return x * (1.0 + gamma[:, :, None, None]) + beta[:, :, None, None]


class TextTokenEncoder(nn.Module):
    """ACT's transformer encoder with the projected sentence embedding as a first token."""

    def __init__(self, encoder: ACTEncoder, dim_model: int, text_dim: int, context: TextContext):
        super().__init__()
        self.encoder = encoder
        self.text_input_proj = nn.Linear(text_dim, dim_model)
        self.context = context

    def forward(self, x: Tensor, pos_embed: Tensor | None = None, **kwargs: Any) -> Tensor:
        token = self.text_input_proj(self.context.current()).to(x.dtype)[None]  # (1, B, D)
        if pos_embed is not None:
            # The token's own projection bias places it; its positional embedding is zero.
            pos_embed = torch.cat([torch.zeros_like(pos_embed[:1]), pos_embed])
        return self.encoder(torch.cat([token, x]), pos_embed=pos_embed, **kwargs)


class TextTokenDecoder(nn.Module):
    """ACT's decoder, given the zero positional embedding of the encoder's text token."""

    def __init__(self, decoder: ACTDecoder):
        super().__init__()
        self.decoder = decoder

    def forward(
        self, x: Tensor, encoder_out: Tensor, encoder_pos_embed: Tensor | None = None, **kwargs: Any
    ) -> Tensor:
        if encoder_pos_embed is not None and len(encoder_pos_embed) + 1 == len(encoder_out):
            encoder_pos_embed = torch.cat(
                [torch.zeros_like(encoder_pos_embed[:1]), encoder_pos_embed]
            )
        return self.decoder(x, encoder_out, encoder_pos_embed=encoder_pos_embed, **kwargs)


def stage_channels(stage: nn.Module) -> int:
    """Output channels of a torchvision ResNet stage (BasicBlock: conv2, Bottleneck: conv3)."""
    last = stage[-1]
    return (last.conv3 if hasattr(last, "conv3") else last.conv2).out_channels


def condition_on_text(model: ACT, config: MTACTConfig, context: TextContext) -> None:
    """Wrap ACT's ResNet stages 1-3 (FiLM) and its encoder/decoder (extra token) in place."""
    text_dim = config.text_embedding_dim
    if config.use_film and config.image_features:
        for name in FILM_STAGES:
            stage = getattr(model.backbone, name)
            # Same key, so IntermediateLayerGetter keeps running the stages in order.
            film = FiLMStage(stage, stage_channels(stage), text_dim, context)
            setattr(model.backbone, name, film)
    model.encoder = TextTokenEncoder(model.encoder, config.dim_model, text_dim, context)
    model.decoder = TextTokenDecoder(model.decoder)


class MTACTPolicy(ACTPolicy):
    """ACT conditioned on ``batch["task"]`` (one string, or one per batch element)."""

    config_class = MTACTConfig
    name = "mt_act"

    def __init__(self, config: MTACTConfig, **kwargs: Any):
        super().__init__(config, **kwargs)
        self.context = TextContext()
        self.text_encoder = TextEncoder(config)
        condition_on_text(self.model, config, self.context)

    def task_embedding(self, batch: dict[str, Any]) -> Tensor:
        """(B, text_dim) embeddings of the batch's task strings, on the policy's device."""
        reference = batch[OBS_STATE] if OBS_STATE in batch else batch[OBS_ENV_STATE]
        if OBS_STATE not in batch and self.config.image_features:
            reference = batch[next(iter(self.config.image_features))]
        size = reference.shape[0]
        tasks = batch.get(TASK)
        if tasks is None:
            raise KeyError(
                f"MT-ACT needs the task string in batch[{TASK!r}] (LeRobot datasets and "
                "lerobot-eval provide it); got keys " + ", ".join(sorted(batch))
            )
        texts: Sequence[str] = [tasks] if isinstance(tasks, str) else list(tasks)
        if len(texts) == 1 and size > 1:
            texts = list(texts) * size
        if len(texts) != size:
            raise ValueError(f"batch[{TASK!r}] has {len(texts)} strings for a batch of {size}")
        # Unit-norm sentence vectors have entries ~ 1/sqrt(dim); scaled to unit RMS, the text
        # token starts as large as the state and image tokens (else it is learned ~20x slower).
        scale = self.config.text_embedding_dim**0.5
        return self.text_encoder(texts).to(reference.device) * scale

    @contextmanager
    def conditioned_on(self, batch: dict[str, Any]) -> Iterator[None]:
        """Make the batch's task embedding visible to the network while inside."""
        self.context.embedding = self.task_embedding(batch)
        try:
            yield
        finally:
            self.context.embedding = None

    @torch.no_grad()
    def predict_action_chunk(self, batch: dict[str, Any]) -> Tensor:
        with self.conditioned_on(batch):
            return super().predict_action_chunk(batch)

    def forward(self, batch: dict[str, Any]) -> tuple[Tensor, dict]:
        with self.conditioned_on(batch):
            return super().forward(batch)
