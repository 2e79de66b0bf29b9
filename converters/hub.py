"""Upload a converted dataset with LeRobot's own ``push_to_hub`` (card, version tag included)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from lerobot.datasets.lerobot_dataset import LeRobotDataset

TAGS = ("RoboManipBaselines", "rmb_lerobot")  # added to the dataset card's tags


def check_repo_id(repo_id: str | None) -> str:
    """Hub datasets are ``namespace/name``; fail before converting, not after."""
    if not repo_id or repo_id.count("/") != 1 or not all(repo_id.split("/")):
        raise ValueError(f"--push-to-hub needs --repo-id NAMESPACE/NAME, got {repo_id!r}")
    return repo_id


def push_dataset(
    repo_id: str,
    root: Path,
    *,
    private: bool = False,
    branch: str | None = None,
    tags: Sequence[str] = (),
) -> None:
    """Upload the dataset at ``root`` to ``repo_id`` (videos, ``meta/rmb.json`` and all)."""
    # Uploading decodes nothing; naming the backend keeps LeRobot from probing torchcodec.
    dataset = LeRobotDataset(check_repo_id(repo_id), root=root, video_backend="pyav")
    dataset.push_to_hub(branch=branch, tags=[*TAGS, *tags], private=private)
