"""LeRobot's pretrained VLAs (pi0, pi05, SmolVLA, GR00T N1.7) on converted RMB datasets.

LeRobot 0.6.1 ships these policies; nothing of them is re-implemented here. What a converted
dataset needs is the glue of a fine-tuning run: which of its cameras fill which of the
checkpoint's camera slots (``--rename_map``), which cameras a VLA can take at all (RGB only: a
depth camera is one channel, which pi0/pi05/SmolVLA/GR00T's image paths reject), and the
checkpoint, chunk sizes and Hub downloads of each recipe (:data:`RECIPES`, used by
:func:`train_args`). The task text is the dataset's own per-episode task (RMB's ``task_desc``,
e.g. Pick's "Put the banana in the blue basket."), which LeRobot hands the policies as
``task``.
"""

from __future__ import annotations

import argparse
import json
import shlex
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from rmb_lerobot import lerobot_names as N
from rmb_lerobot.errors import RmbFormatError

PI_CAMERA_SLOTS = tuple(
    N.image_key(slot) for slot in ("base_0_rgb", "left_wrist_0_rgb", "right_wrist_0_rgb")
)
SMOLVLA_CAMERA_SLOTS = tuple(N.image_key(f"camera{i}") for i in (1, 2, 3))
PALIGEMMA_TOKENIZER = "google/paligemma-3b-pt-224"  # gated: accept its licence on the Hub first


@dataclass(frozen=True)
class VLARecipe:
    """How LeRobot fine-tunes one pretrained VLA.

    Attributes:
        policy_type: ``--policy.type`` / the ``type`` in the checkpoint's config.
        checkpoint: The Hub id of the base checkpoint.
        camera_slots: The checkpoint's image keys, scene camera first then wrist cameras; empty
            where the policy takes the dataset's own camera names (GR00T).
        chunk_size: Actions predicted per inference (the checkpoint's value).
        n_action_steps: Actions executed from each chunk.
        downloads: Hub repositories fetched when the policy and its processors are built.
    """

    policy_type: str
    checkpoint: str
    camera_slots: tuple[str, ...]
    chunk_size: int
    n_action_steps: int
    downloads: tuple[str, ...]


RECIPES: dict[str, VLARecipe] = {
    "pi0": VLARecipe(
        "pi0",
        "lerobot/pi0_base",
        PI_CAMERA_SLOTS,
        50,
        50,
        ("lerobot/pi0_base", PALIGEMMA_TOKENIZER),
    ),
    "pi05": VLARecipe(
        "pi05",
        "lerobot/pi05_base",
        PI_CAMERA_SLOTS,
        50,
        50,
        ("lerobot/pi05_base", PALIGEMMA_TOKENIZER),
    ),
    "smolvla": VLARecipe(
        "smolvla",
        "lerobot/smolvla_base",
        SMOLVLA_CAMERA_SLOTS,
        50,
        50,
        ("lerobot/smolvla_base", "HuggingFaceTB/SmolVLM2-500M-Video-Instruct"),
    ),
    "groot": VLARecipe(
        "groot",
        "nvidia/GR00T-N1.7-3B",
        (),
        40,
        40,
        ("nvidia/GR00T-N1.7-3B", "nvidia/Cosmos-Reason2-2B"),
    ),
}


def _recipe(policy: str) -> VLARecipe:
    if policy not in RECIPES:
        raise ValueError(f"unknown VLA {policy!r}; expected one of {sorted(RECIPES)}")
    return RECIPES[policy]


def read_features(dataset_root: str | Path) -> dict[str, dict]:
    """The ``features`` of a LeRobotDataset's ``meta/info.json``."""
    path = Path(dataset_root) / "meta" / "info.json"
    try:
        return json.loads(path.read_text())["features"]
    except (OSError, ValueError, KeyError) as error:
        raise RmbFormatError(f"cannot read the dataset features ({error})", path=path) from error


def rgb_cameras(features: dict[str, dict]) -> list[str]:
    """The RGB camera names of a dataset's ``features`` (depth cameras left out), in order."""
    cameras = []
    for key, feature in features.items():
        camera = N.camera_of_image_key(key)
        is_depth = (feature.get("info") or {}).get("video.is_depth_map") or (
            feature.get("info") or {}
        ).get("is_depth_map")
        if camera is None or feature.get("dtype") not in ("video", "image") or is_depth:
            continue
        if feature["shape"][-1] == 3:
            cameras.append(camera)
    return cameras


def is_wrist_camera(camera: str) -> bool:
    """RMB names wrist cameras ``hand``, ``left_hand``, ``right_hand``."""
    return camera == "hand" or camera.endswith("_hand")


def camera_rename_map(cameras: list[str], policy: str) -> dict[str, str]:
    """Dataset image keys -> the checkpoint's camera slots (``--rename_map``).

    The first scene camera (``front``, ``left``, ...) comes first, then the wrist cameras, then
    the other scene cameras, each group in the dataset's order. pi0/pi05 put the first scene
    camera in ``base_0_rgb`` and the wrist cameras in ``left_wrist_0_rgb`` then
    ``right_wrist_0_rgb`` (RMB's dual arms list ``left`` first); SmolVLA fills ``camera1..3``
    in the same order (scene, wrist, then a second wrist or scene camera), so all three see the
    same cameras and a dataset recorded with every scene camera still gives SmolVLA its wrist
    view. Cameras beyond the slots are not renamed, so the policy does not see them; pi0/pi05
    mask their empty slots, SmolVLA leaves them out (``--policy.empty_cameras=N`` adds N blank,
    masked ones). GR00T takes the dataset's names: an empty map.
    """
    recipe = _recipe(policy)
    if not recipe.camera_slots:
        return {}
    scene = [c for c in cameras if not is_wrist_camera(c)]
    wrist = [c for c in cameras if is_wrist_camera(c)]
    if not scene and not wrist:
        raise ValueError(f"{policy} needs at least one RGB camera, the dataset has none")
    if recipe.camera_slots == PI_CAMERA_SLOTS:
        pairs = list(zip(scene[:1], recipe.camera_slots[:1], strict=False))
        pairs += list(zip(wrist, recipe.camera_slots[1:], strict=False))
    else:
        pairs = list(zip(scene[:1] + wrist + scene[1:], recipe.camera_slots, strict=False))
    return {N.image_key(camera): slot for camera, slot in pairs}


def train_args(
    dataset_root: str | Path,
    policy: str,
    *,
    repo_id: str | None = None,
    checkpoint: str | None = None,
) -> list[str]:
    """``lerobot-train`` arguments fine-tuning ``policy``'s base checkpoint (or ``checkpoint``,
    e.g. a local copy) on the converted dataset at ``dataset_root``; add ``--output_dir``,
    ``--steps``, ``--batch_size``, ``--policy.device`` and the like. pi0/pi05/SmolVLA keep
    their checkpoint's chunk sizes (``--policy.chunk_size=...`` after these overrides them)."""
    recipe = _recipe(policy)
    root = Path(dataset_root)
    features = read_features(root)
    cameras = rgb_cameras(features)
    depth = [N.camera_of_image_key(k) for k in features if N.camera_of_image_key(k)]
    depth = [c for c in depth if c not in cameras]
    if depth:
        raise RmbFormatError(
            f"{policy} takes RGB cameras only, but the dataset has depth cameras {depth}; "
            "convert it again without --depth for VLA fine-tuning",
            path=root / "meta" / "info.json",
        )
    args = [f"--dataset.repo_id={repo_id or f'local/{root.name}'}", f"--dataset.root={root}"]
    if policy == "groot":
        # GR00T builds a fresh LeRobot policy around the base model (not a LeRobot checkpoint).
        args += [
            "--policy.type=groot",
            f"--policy.base_model_path={checkpoint or recipe.checkpoint}",
            "--policy.embodiment_tag=new_embodiment",
            f"--policy.chunk_size={recipe.chunk_size}",
            f"--policy.n_action_steps={recipe.n_action_steps}",
        ]
    else:
        args += [
            f"--policy.path={checkpoint or recipe.checkpoint}",
            f"--rename_map={json.dumps(camera_rename_map(cameras, policy))}",
        ]
    return args


def train_command(dataset_root: str | Path, policy: str, **kwargs: str | None) -> str:
    """The ``lerobot-train`` command of :func:`train_args` as one line to paste into a shell.

    Every argument is shell-quoted (:func:`shlex.join`): ``--rename_map``'s JSON holds quotes
    and spaces, which a plain ``" ".join`` hands bash as several broken words.

    Args:
        dataset_root: The converted dataset's directory.
        policy: The recipe (:data:`RECIPES`: pi0, pi05, smolvla, groot).
        **kwargs: ``repo_id`` and ``checkpoint``, as for :func:`train_args`.

    Returns:
        E.g. ``lerobot-train --policy.path=lerobot/pi0_base ... '--rename_map={"..."}'``.
    """
    return shlex.join(["lerobot-train", *train_args(dataset_root, policy, **kwargs)])


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m rmb_lerobot.policies_extra.vla DATASET POLICY``: print the command line."""
    parser = argparse.ArgumentParser(
        prog="python -m rmb_lerobot.policies_extra.vla",
        description="Print the lerobot-train command (shell-quoted) that fine-tunes a VLA on a "
        "converted dataset; add --output_dir, --steps, --batch_size, --policy.device.",
    )
    parser.add_argument("dataset", type=Path, help="the converted dataset's directory")
    parser.add_argument("policy", choices=sorted(RECIPES), help="the VLA recipe")
    parser.add_argument("--repo-id", help="dataset id (default: local/DATASET_NAME)")
    parser.add_argument("--checkpoint", help="base checkpoint (default: the recipe's Hub id)")
    args = parser.parse_args(argv)
    try:
        command = train_command(
            args.dataset, args.policy, repo_id=args.repo_id, checkpoint=args.checkpoint
        )
    except (RmbFormatError, ValueError) as error:
        print(f"{parser.prog}: error: {error}", file=sys.stderr)
        return 2
    print(command)
    return 0


if __name__ == "__main__":
    sys.exit(main())
