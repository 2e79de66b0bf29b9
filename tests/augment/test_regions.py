"""Acceptable regions: the YAML file, its errors, and proposals at gripper events."""

from __future__ import annotations

import numpy as np
import pytest

from rmb_lerobot.augment import (
    Region,
    dump_regions,
    gripper_events,
    load_regions,
    propose_regions,
)
from rmb_lerobot.errors import RmbFormatError


def test_regions_round_trip_through_yaml(tmp_path):
    path = tmp_path / "regions.yaml"
    path.write_text(
        "regions:\n"
        "  - {time_idx: 30, radius: 0.03}\n"
        "  - {time_idx: 12, radius: 0.01, convergence_idx: 14, max_rotation_deg: 5}\n"
    )
    regions = load_regions(path, demo_length=44)
    assert regions == [
        Region(30, 0.03),
        Region(12, 0.01, convergence_idx=14, max_rotation_deg=5.0),
    ]
    assert [r.end_idx for r in regions] == [30, 14]
    assert regions[0].max_rotation_rad(rotation_scale=2.0) == pytest.approx(0.06)
    assert regions[1].max_rotation_rad(rotation_scale=2.0) == pytest.approx(np.deg2rad(5))
    assert load_regions(dump_regions(regions, tmp_path / "again.yaml")) == regions


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (
            "regions:\n  - {time_idx: 3}\n",
            r"missing required field 'radius'.*key 'regions\[0\]\.radius'",
        ),
        (
            "regions:\n  - {time_idx: 3, radius: -0.1}\n",
            r"radius must be in \(0, 0.25\].*regions\[0\]\.radius",
        ),
        (
            "regions:\n  - {time_idx: 3, radius: 0.02}\n  - {time_idx: 50, radius: 0.02}\n",
            r"time_idx must be a step of the demo in 0\.\.42.*got 50.*regions\[1\]\.time_idx",
        ),
        ("regions:\n  - {time_idx: 2.5, radius: 0.02}\n", r"integer step index, got 2\.5"),
        ("regions:\n  - {time_idx: 3, radius: fast}\n", r"expected a number, got 'fast'"),
        (
            "regions:\n  - {time_idx: 3, radius: 0.02, centre: 1}\n",
            r"unknown field\(s\) \['centre'\]",
        ),
        ("regions: []\n", r"non-empty list of regions"),
        ("spheres:\n  - {time_idx: 3, radius: 0.02}\n", r"top-level 'regions' list"),
        ("regions: [\n", r"not valid YAML"),
        ("regions:\n  - 3\n", r"each region must be a mapping"),
    ],
)
def test_region_file_errors_name_the_file_and_the_field(tmp_path, text, message):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(RmbFormatError, match=message) as info:
        load_regions(path, demo_length=44)
    assert "bad.yaml" in str(info.value)


def test_a_missing_region_file_is_named(tmp_path):
    with pytest.raises(RmbFormatError, match=r"regions file not found.*nowhere\.yaml"):
        load_regions(tmp_path / "nowhere.yaml")


def _gripper(length: int, closed: tuple[int, int] | None) -> np.ndarray:
    g = np.zeros((length, 1))
    if closed is not None:
        g[closed[0] : closed[1]] = 255.0
    return g


@pytest.mark.parametrize(("close", "open_"), [(10, 30), (5, 40), (20, 21)])
def test_proposed_regions_sit_at_the_gripper_events(close, open_):
    gripper = _gripper(50, (close, open_))
    assert gripper_events(gripper) == [(close, "close"), (open_, "open")]
    path = np.cumsum(np.full((50, 3), 0.01), axis=0)
    regions = propose_regions(gripper, path, radius=0.015)
    # Centred on the last step before the command changes: the hand in place, as it was.
    assert [(r.time_idx, r.event) for r in regions] == [(close - 1, "close"), (open_ - 1, "open")]
    assert all(r.radius == 0.015 for r in regions)


def test_a_demo_without_gripper_events_gets_a_region_at_its_final_approach():
    """Insert holds its peg throughout: the region goes where the path turns down to the hole."""
    gripper = _gripper(40, None)
    assert gripper_events(gripper) == []
    across = np.stack([np.linspace(0, 0.3, 25), np.zeros(25), np.full(25, 0.2)], axis=1)
    down = np.stack([np.full(15, 0.3), np.zeros(15), np.linspace(0.19, 0.05, 15)], axis=1)
    regions = propose_regions(gripper, np.vstack([across, down]))
    assert len(regions) == 1
    assert regions[0].event == "approach"
    assert 23 <= regions[0].time_idx <= 26
