"""Tiny stand-ins for what LeRobot's VLAs download: a tokenizer built here, pi0/pi05 networks
shrunk to a few thousand parameters per layer, and a local GR00T N1.7 checkpoint with a tiny
Qwen3-VL backbone (config, tokenizer with chat template, image/video processors), and a tiny
SmolVLM2 with a stand-in ``lerobot/smolvla_base`` around it for SmolVLA.

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


# ------------------------------------------------------------------ SmolVLA, tiny and local
SMOLVLM_SPECIALS = {  # the named special tokens of SmolVLM2's tokenizer (extra_special_tokens)
    "fake_image_token": "<fake_token_around_image>",
    "image_token": "<image>",
    "global_image_token": "<global-img>",
    "end_of_utterance_token": "<end_of_utterance>",
    "video_token": "<video>",
}
SMOLVLM_CHAT_TEMPLATE = (
    "<|im_start|>{% for m in messages %}{{ m['role'] | capitalize }}: "
    "{% for c in m['content'] %}{% if c['type'] == 'text' %}{{ c['text'] }}"
    "{% elif c['type'] == 'image' %}<image>{% endif %}{% endfor %}<end_of_utterance>\n"
    "{% endfor %}{% if add_generation_prompt %}Assistant:{% endif %}"
)


def build_smolvlm(directory: Path, texts: Sequence[str]) -> Path:
    """A tiny SmolVLM2 saved as ``HuggingFaceTB/SmolVLM2-500M-Video-Instruct`` is laid out:
    config (2-layer, 64-wide Llama text model; 1-layer, 32-wide SigLIP tower on 512x512 images
    in 32-pixel patches; pixel-shuffle scale 4, so 16 tokens per image), random weights, image
    and video processors, and a WordLevel tokenizer with SmolVLM's named image tokens (SmolVLA
    reads ``fake_image_token_id`` / ``global_image_token_id`` from it)."""
    from tokenizers import Tokenizer, models, pre_tokenizers, trainers
    from transformers import (
        PreTrainedTokenizerFast,
        SmolVLMConfig,
        SmolVLMForConditionalGeneration,
        SmolVLMImageProcessor,
        SmolVLMProcessor,
    )
    from transformers.models.smolvlm import SmolVLMVideoProcessor

    directory = Path(directory)
    tokenizer = Tokenizer(models.WordLevel(unk_token="<unk>"))
    tokenizer.pre_tokenizer = pre_tokenizers.Whitespace()
    specials = ["<|endoftext|>", "<|im_start|>", "<unk>", *SMOLVLM_SPECIALS.values()]
    tokenizer.train_from_iterator(
        [*texts, "User Assistant"], trainers.WordLevelTrainer(special_tokens=specials)
    )
    assert tokenizer.get_vocab_size() < VOCAB
    fast = PreTrainedTokenizerFast(
        tokenizer_object=tokenizer,
        bos_token="<|im_start|>",
        eos_token="<end_of_utterance>",
        pad_token="<|endoftext|>",
        unk_token="<unk>",
        extra_special_tokens=dict(SMOLVLM_SPECIALS),
    )
    image_size, patch, scale = 512, 32, 4
    image_processor = SmolVLMImageProcessor(
        do_image_splitting=False,
        max_image_size={"longest_edge": image_size},
        size={"longest_edge": image_size},
    )
    video_processor = SmolVLMVideoProcessor(
        max_image_size={"longest_edge": image_size}, size={"longest_edge": image_size}
    )
    processor = SmolVLMProcessor(
        image_processor,
        fast,
        video_processor,
        image_seq_len=(image_size // patch) ** 2 // scale**2,
        chat_template=SMOLVLM_CHAT_TEMPLATE,
    )
    processor.save_pretrained(directory)
    config = SmolVLMConfig(
        image_token_id=fast.convert_tokens_to_ids(SMOLVLM_SPECIALS["image_token"]),
        pad_token_id=fast.pad_token_id,
        scale_factor=scale,
        vision_config={
            "hidden_size": 32,
            "intermediate_size": 64,
            "num_hidden_layers": 1,
            "num_attention_heads": 2,
            "image_size": image_size,
            "patch_size": patch,
        },
        text_config={
            "model_type": "llama",
            "hidden_size": WIDTH,
            "intermediate_size": 2 * WIDTH,
            "num_hidden_layers": 2,
            "num_attention_heads": 4,
            "num_key_value_heads": 2,
            "head_dim": 16,
            "vocab_size": VOCAB,
            "pad_token_id": fast.pad_token_id,
        },
    )
    SmolVLMForConditionalGeneration(config).save_pretrained(directory)
    return directory


def build_smolvla_base(directory: Path, backbone: Path, backbone_name: str) -> Path:
    """A stand-in for ``lerobot/smolvla_base``: its config (camera slots ``camera1..3`` at
    256x256, 6-d state and action, chunk 50, ``load_vlm_weights``, the 16-layer cut, cross
    attention every other layer, 0.75-wide expert, language padded to 48 tokens) around the
    tiny SmolVLM at ``backbone``, saved with its pre/post-processors and ``backbone_name`` (the
    Hub id) as the VLM and tokenizer name, exactly where the real checkpoint names it."""
    from lerobot.configs.types import FeatureType, PolicyFeature
    from lerobot.policies.factory import make_pre_post_processors
    from lerobot.policies.smolvla import SmolVLAConfig, SmolVLAPolicy
    from lerobot.processor import TokenizerProcessorStep

    cameras = {
        f"observation.images.camera{i}": PolicyFeature(FeatureType.VISUAL, (3, 256, 256))
        for i in (1, 2, 3)
    }
    config = SmolVLAConfig(
        input_features={**cameras, "observation.state": PolicyFeature(FeatureType.STATE, (6,))},
        output_features={"action": PolicyFeature(FeatureType.ACTION, (6,))},
        vlm_model_name=str(backbone),
        load_vlm_weights=True,
        pad_language_to="max_length",
        prefix_length=0,
        num_expert_layers=0,
        device="cpu",
    )
    policy = SmolVLAPolicy(config)
    pre, post = make_pre_post_processors(config, dataset_stats={})
    config.vlm_model_name = backbone_name
    (tokenizer_step,) = [s for s in pre.steps if isinstance(s, TokenizerProcessorStep)]
    tokenizer_step.tokenizer_name = backbone_name
    for part in (policy, pre, post):
        part.save_pretrained(directory)
    return Path(directory)


def seed_hub_cache(cache: Path, repo_id: str, files: Path) -> None:
    """Put ``files`` in a Hugging Face cache (``HF_HUB_CACHE``) as the snapshot of model
    ``repo_id``, where an offline ``from_pretrained(repo_id)`` finds it."""
    import shutil

    repo = Path(cache) / f"models--{repo_id.replace('/', '--')}"
    revision = "0" * 40
    shutil.copytree(files, repo / "snapshots" / revision)
    (repo / "refs").mkdir()
    (repo / "refs" / "main").write_text(revision)


def lerobot_train_two_steps(
    args: Sequence[str], workdir: Path, *, hub_cache: Path | None = None, patched: bool = False
) -> tuple[str, Path]:
    """Run ``lerobot-train ARGS`` for 2 CPU steps, offline; return its stdout and the saved
    pretrained model.

    ``hub_cache``: the Hugging Face cache (``HF_HUB_CACHE``) that answers the Hub ids in ARGS.
    ``patched``: run it through this module's ``lerobot_train`` entry (pi0's network sizes are
    not config fields, so they are shrunk in that process); otherwise LeRobot's own module.
    """
    import os
    import subprocess

    out = Path(workdir) / "train"
    args = [*args, "--policy.device=cpu", "--policy.push_to_hub=false", f"--output_dir={out}"]
    args += ["--steps=2", "--batch_size=2", "--num_workers=0", "--save_freq=2"]
    args += ["--log_freq=1", "--wandb.enable=false"]
    env = {**os.environ, "HF_HUB_OFFLINE": "1", "WANDB_MODE": "disabled"}
    if hub_cache is not None:
        env["HF_HUB_CACHE"] = str(hub_cache)
    entry = [__file__, "lerobot_train"] if patched else ["-m", "lerobot.scripts.lerobot_train"]
    run = subprocess.run(
        [sys.executable, *entry, *args],
        cwd=workdir,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 0, run.stderr[-3000:]
    return run.stdout, out / "checkpoints" / "last" / "pretrained_model"
