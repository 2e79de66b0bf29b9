"""Tiny stand-ins for what LeRobot's VLAs download: a tokenizer built here, pi0/pi05 networks
shrunk to a few thousand parameters per layer, and a local GR00T N1.7 checkpoint with a tiny
Qwen3-VL backbone (config, tokenizer with chat template, image/video processors).

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


# ------------------------------------------------------------------ GR00T N1.7, tiny and local
QWEN_SPECIALS = (
    "<|endoftext|>",
    "<|im_start|>",
    "<|im_end|>",
    "<|vision_start|>",
    "<|vision_end|>",
    "<|image_pad|>",
    "<|video_pad|>",
)
# A Qwen-style chat template: each image becomes vision_start, image_pad, vision_end.
QWEN_CHAT_TEMPLATE = (
    "{% for m in messages %}<|im_start|>{{ m['role'] }}\n"
    "{% for c in m['content'] %}{% if c['type'] == 'image' %}"
    "<|vision_start|><|image_pad|><|vision_end|>{% elif c['type'] == 'text' %}{{ c['text'] }}"
    "{% endif %}{% endfor %}<|im_end|>\n{% endfor %}"
)


def build_qwen3_vl(directory: Path, texts: Sequence[str]) -> Path:
    """A 2-layer, 64-wide Qwen3-VL config with its tokenizer (chat template, vision tokens),
    image and video processors: what GR00T N1.7 fetches from ``nvidia/Cosmos-Reason2-2B``."""
    from tokenizers import Tokenizer, models, pre_tokenizers, trainers
    from transformers import PreTrainedTokenizerFast, Qwen2VLImageProcessor, Qwen3VLConfig
    from transformers.models.qwen3_vl import Qwen3VLVideoProcessor

    directory = Path(directory)
    tokenizer = Tokenizer(models.WordLevel(unk_token="<unk>"))
    tokenizer.pre_tokenizer = pre_tokenizers.Whitespace()
    specials = [*QWEN_SPECIALS, "<unk>"]
    tokenizer.train_from_iterator(
        [*texts, "user assistant"], trainers.WordLevelTrainer(special_tokens=specials)
    )
    fast = PreTrainedTokenizerFast(
        tokenizer_object=tokenizer, pad_token="<|endoftext|>", unk_token="<unk>"
    )
    fast.chat_template = QWEN_CHAT_TEMPLATE
    fast.save_pretrained(directory)
    ids = {token: fast.convert_tokens_to_ids(token) for token in QWEN_SPECIALS}
    patch = 16
    Qwen2VLImageProcessor(patch_size=patch, temporal_patch_size=2, merge_size=2).save_pretrained(
        directory
    )
    Qwen3VLVideoProcessor(patch_size=patch, temporal_patch_size=2, merge_size=2).save_pretrained(
        directory
    )
    Qwen3VLConfig(
        image_token_id=ids["<|image_pad|>"],
        video_token_id=ids["<|video_pad|>"],
        vision_start_token_id=ids["<|vision_start|>"],
        vision_end_token_id=ids["<|vision_end|>"],
        tie_word_embeddings=True,
        text_config={
            "head_dim": 16,
            "hidden_size": WIDTH,
            "intermediate_size": 2 * WIDTH,
            "num_attention_heads": 4,
            "num_hidden_layers": 2,
            "num_key_value_heads": 2,
            "rope_scaling": {"mrope_interleaved": True, "mrope_section": [4, 2, 2]},
            "vocab_size": VOCAB,
            "tie_word_embeddings": True,
        },
        vision_config={
            "deepstack_visual_indexes": [0],
            "depth": 1,
            "hidden_size": 32,
            "intermediate_size": 64,
            "num_heads": 2,
            "out_hidden_size": WIDTH,
            "patch_size": patch,
            "spatial_merge_size": 2,
            "temporal_patch_size": 2,
        },
    ).save_pretrained(directory)
    return directory


def build_groot_checkpoint(directory: Path, backbone: Path, action_horizon: int) -> Path:
    """A raw GR00T N1.7 checkpoint (config.json without a LeRobot ``type``, weights) whose
    backbone is ``backbone`` (:func:`build_qwen3_vl`) and whose action head is a 2-layer DiT."""
    from lerobot.policies.groot.groot_n1_7 import GR00TN17, GR00TN17Config

    heads = {"num_attention_heads": 4, "attention_head_dim": WIDTH // 4}
    config = GR00TN17Config(
        model_name=str(backbone),
        backbone_model_type="qwen",
        backbone_embedding_dim=WIDTH,
        select_layer=2,
        hidden_size=WIDTH,
        input_embedding_dim=WIDTH,
        action_horizon=action_horizon,
        max_seq_len=256,
        diffusion_model_cfg={
            "positional_embeddings": None,
            "num_layers": 2,
            **heads,
            "norm_type": "ada_norm",
            "dropout": 0.0,
            "final_dropout": True,
            "output_dim": WIDTH,
            "interleave_self_attention": True,
        },
        vl_self_attention_cfg={
            "positional_embeddings": None,
            "num_layers": 1,
            **heads,
            "dropout": 0.0,
            "final_dropout": True,
        },
        state_dropout_prob=0.0,
    )
    GR00TN17(config, load_backbone_weights=False).save_pretrained(directory)
    return Path(directory)
