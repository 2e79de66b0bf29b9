"""Fixtures for the rmb-data tools: episodes with extra keys, and a lerobot-eval output dir."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from rmb_lerobot import EpisodeWriter
from rmb_lerobot.kinematics import UR5E


@pytest.fixture
def record_with(steps, attrs):
    """``record_with(path, extra=fn(i) -> dict, attrs=..., num_steps=...)``: the synthetic
    episode with extra keys per step (e.g. a tactile grid) or other attributes."""

    def _record(path: Path, extra=None, num_steps: int | None = None, **attr_overrides) -> Path:
        with EpisodeWriter(path, {**attrs, **attr_overrides}, fk=UR5E) as writer:
            for i, step in enumerate(steps[:num_steps]):
                writer.append({**step, **(extra(i) if extra else {})})
        return path

    return _record


def _write_eval_output(root: Path, successes: dict[str, list[bool]], sizes=(64, 48)) -> Path:
    """What lerobot-eval leaves in its output dir: ``videos/<env>_<task>/eval_episode_K.mp4``
    (written with LeRobot's own write_video) and ``eval_info.json`` with per-task successes.
    Episode K of task T shows grey level 20 * K + 100 * T and lasts 6 + K frames."""
    from lerobot.utils.io_utils import write_video

    per_task = []
    width, height = sizes
    for t, (task, outcomes) in enumerate(successes.items()):
        directory = root / "videos" / task
        directory.mkdir(parents=True)
        paths = []
        for k in range(len(outcomes)):
            frames = [np.full((height, width, 3), 20 * k + 100 * t, np.uint8)] * (6 + k)
            path = directory / f"eval_episode_{k}.mp4"
            write_video(str(path), frames, 10)
            paths.append(str(path.resolve()))
        group, task_id = task.rsplit("_", 1)
        metrics = {"successes": outcomes, "video_paths": paths, "sum_rewards": [0.0] * len(paths)}
        per_task.append({"task_group": group, "task_id": int(task_id), "metrics": metrics})
    (root / "eval_info.json").write_text(json.dumps({"per_task": per_task, "overall": {}}))
    return root


@pytest.fixture
def write_eval_output():
    """``write_eval_output(root, {"<env>_<task>": [success, ...]})``: a lerobot-eval output."""
    return _write_eval_output


@pytest.fixture
def eval_output(tmp_path) -> Path:
    """Five rollouts of one task: successes 1 0 1 0 0."""
    return _write_eval_output(
        tmp_path / "eval", {"rmb_ur5e_insert_0": [True, False, True, False, False]}
    )
