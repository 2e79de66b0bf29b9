"""``rmb-augment``: a scripted demo in, complete augmented RMB episodes out."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rmb_lerobot import find_episodes, open_episode
from rmb_lerobot.augment import load_regions
from rmb_lerobot.cli import augment as augment_cli
from rmb_lerobot.cli import collect as collect_cli


@pytest.fixture(scope="module")
def demo(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("demo")
    argv = ["insert", "--episodes=1", f"--out={out}", "--world-idx=1", "--cameras", "hand"]
    assert collect_cli.main([*argv, "--image-size", "32", "32", "--no-depth"]) == 0
    (path,) = find_episodes(out)
    return path


def test_proposed_regions_are_written_and_augmented(demo, tmp_path, capsys):
    out = tmp_path / "aug"
    argv = [
        "insert",
        str(demo),
        "--propose-regions",
        "--samples-per-region=2",
        f"--out={out}",
        "--radius=0.02",
        "--duration=0.5",
        "--seed=7",
    ]
    assert augment_cli.main(argv) == 0
    assert "wrote 2 augmented episodes" in capsys.readouterr().out
    (region,) = load_regions(out / "regions.yaml")
    assert region.event == "approach"  # Insert's peg is held throughout: no gripper events
    episodes = find_episodes(out)
    assert [p.name for p in episodes] == [
        f"{demo.stem}_augmented_region000_00.rmb",
        f"{demo.stem}_augmented_region000_01.rmb",
    ]
    with open_episode(demo) as base:
        remainder = len(base) - region.end_idx - 1
        last = base["measured_joint_pos"][-1]
    for path in episodes:
        with open_episode(path) as ep:
            ep.validate(frames=True)
            # the reversed motion (cut where it joins the demo) and at most the demo's remainder
            assert remainder < len(ep) <= round(0.5 / 0.032) + 1 + remainder
            np.testing.assert_array_equal(ep["measured_joint_pos"][-1], last)


@pytest.mark.parametrize(
    ("yaml_text", "message"),
    [
        ("regions:\n  - {time_idx: 5}\n", "missing required field 'radius'"),
        ("regions:\n  - {time_idx: 9999, radius: 0.02}\n", "time_idx must be a step of the demo"),
    ],
)
def test_a_bad_regions_file_is_reported_and_nothing_written(
    demo, tmp_path, capsys, yaml_text, message
):
    regions = tmp_path / "regions.yaml"
    regions.write_text(yaml_text)
    out = tmp_path / "aug"
    argv = ["insert", str(demo), f"--regions={regions}", "--samples-per-region=1", f"--out={out}"]
    assert augment_cli.main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("rmb-augment: error: ")
    assert message in err and "regions.yaml" in err and "regions[0]" in err
    assert not out.exists() or not find_episodes(out)


def test_a_demo_of_another_env_is_refused(demo, tmp_path, capsys):
    argv = ["door", str(demo), "--propose-regions", "--samples-per-region=1", f"--out={tmp_path}"]
    assert augment_cli.main(argv) == 2
    assert "recorded in 'MujocoUR5eInsertEnv'" in capsys.readouterr().err
