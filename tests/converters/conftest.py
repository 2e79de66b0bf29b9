"""Shared converter fixtures: scripted demos recorded once, converted once per module.

Everything is tiny (32x32 images, two ~40-step Insert episodes) so the whole directory runs in
about two minutes on two cores; LeRobot's import dominates.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from rmb_lerobot.converters import ConvertOptions, to_lerobot
from rmb_lerobot.envs.collect import CollectConfig, collect

CAMERAS = ("front", "hand")


@pytest.fixture(scope="session")
def demos(tmp_path_factory) -> Path:
    """Two Insert demonstrations by the scripted expert (worlds 0 and 1), RGB + depth."""
    out = tmp_path_factory.mktemp("demos")
    config = CollectConfig("insert", out, episodes=2, cameras=CAMERAS, image_size=(32, 32))
    results = list(collect(config))
    assert all(r.success for r in results)
    return out


@pytest.fixture
def demo_copy(demos, tmp_path) -> Path:
    """A private copy of the demos, for tests that damage or add episodes."""
    return Path(shutil.copytree(demos, tmp_path / "demos"))


@pytest.fixture(scope="session")
def converted_depth(demos, tmp_path_factory) -> Path:
    """The demos as a LeRobotDataset with depth, LeRobot's default (AV1) RGB codec."""
    root = tmp_path_factory.mktemp("datasets") / "insert_depth"
    to_lerobot([demos], output=root, options=ConvertOptions(depth=True), progress=False)
    return root


@pytest.fixture
def hidden_entries():
    """Names of hidden entries (staging directories) in a directory."""

    def _hidden(directory: Path) -> list[str]:
        return sorted(p.name for p in directory.iterdir() if p.name.startswith("."))

    return _hidden
