"""Tiny stand-ins for what LeRobot's VLAs download: a tokenizer built here, and pi0/pi05
networks shrunk to a few thousand parameters per layer.

pi0's and pi05's sizes are not config fields: ``get_gemma_config`` maps the variant names
(``gemma_2b``, ``gemma_300m``) to fixed widths and PaliGemma's SigLIP tower is built with its
400M-parameter defaults. :func:`tiny_pi_networks` swaps those three construction points for tiny
ones (everything else, from the processors to the flow-matching loss, is LeRobot's own code).
Run as a script, this module applies the same patch and then runs ``lerobot-train``'s unmodified
``main`` with the remaining arguments, so the CLI can be tested in a subprocess.
"""

from __future__ import annotations

import contextlib
import runpy
import sys
from collections.abc import Iterator, Sequence
from pathlib import Path
from unittest import mock

WIDTH, HEAD_DIM = 64, 8  # pi0's attention code hard-codes 8 query heads: width = 8 * head_dim
VOCAB = 256
SPECIALS = ("<pad>", "<unk>", "<bos>", "<eos>")


def build_tokenizer(directory: Path, texts: Sequence[str]) -> Path:
    """A WordLevel tokenizer over the words of ``texts`` (plus specials), saved as a
    ``PreTrainedTokenizerFast`` that ``AutoTokenizer.from_pretrained(directory)`` loads."""
    from tokenizers import Tokenizer, models, pre_tokenizers, trainers
    from transformers import PreTrainedTokenizerFast

    tokenizer = Tokenizer(models.WordLevel(unk_token="<unk>"))
    tokenizer.pre_tokenizer = pre_tokenizers.Whitespace()
    tokenizer.train_from_iterator(texts, trainers.WordLevelTrainer(special_tokens=list(SPECIALS)))
    assert tokenizer.get_vocab_size() < VOCAB
    fast = PreTrainedTokenizerFast(
        tokenizer_object=tokenizer,
        pad_token="<pad>",
        unk_token="<unk>",
        bos_token="<bos>",
        eos_token="<eos>",
    )
    fast.save_pretrained(directory)
    return Path(directory)


@contextlib.contextmanager
def tiny_pi_networks() -> Iterator[None]:
    """While active, pi0 and pi05 build a 1-layer, 64-wide PaliGemma + action expert with a
    1-layer, 32-wide SigLIP tower and a 256-token vocabulary, whatever the variant names."""
    from lerobot.policies.pi0 import modeling_pi0
    from lerobot.policies.pi05 import modeling_pi05

    def gemma_config(variant: str):
        return modeling_pi0.GemmaConfig(
            width=WIDTH, depth=1, mlp_dim=2 * WIDTH, num_heads=8, num_kv_heads=1, head_dim=HEAD_DIM
        )

    def vlm(original):
        def build(config):
            vision = config.vision_config
            vision.hidden_size, vision.intermediate_size = 32, 64
            vision.num_hidden_layers, vision.num_attention_heads = 1, 2
            vision.patch_size = 8
            vision.projection_dim = config.text_config.hidden_size
            config.text_config.vocab_size = VOCAB
            return original(config=config)

        return build

    def expert(original):
        def build(config):
            config.vocab_size = VOCAB
            return original(config=config)

        return build

    with contextlib.ExitStack() as stack:
        for module in (modeling_pi0, modeling_pi05):
            stack.enter_context(mock.patch.object(module, "get_gemma_config", gemma_config))
            name = "PaliGemmaForConditionalGenerationWithPiGemma"
            stack.enter_context(mock.patch.object(module, name, vlm(getattr(module, name))))
            name = "PiGemmaForCausalLM"
            stack.enter_context(mock.patch.object(module, name, expert(getattr(module, name))))
        yield


def main(argv: Sequence[str]) -> None:
    """``python tiny_vla.py lerobot_train ARGS...``: the LeRobot CLI with tiny pi networks."""
    module, *args = argv
    sys.argv = [module, *args]
    with tiny_pi_networks():
        runpy.run_module(f"lerobot.scripts.{module}", run_name="__main__")


if __name__ == "__main__":
    main(sys.argv[1:])
