"""to-lerobot --depth: a listed camera's missing depth file and NaN/inf depth are refused."""

from __future__ import annotations

import logging
from pathlib import Path

import h5py
import numpy as np
import pytest
from lerobot.datasets.lerobot_dataset import LeRobotDatasetMetadata

from rmb_lerobot import RmbFormatError
from rmb_lerobot import lerobot_names as N
from rmb_lerobot.cli.convert import main
from rmb_lerobot.converters import ConvertOptions, to_lerobot


def _convert(src: Path, dest: Path, **options):
    return to_lerobot(
        [src], output=dest, options=ConvertOptions(**options), video_codec="h264", progress=False
    )


@pytest.fixture
def no_hand_depth(tmp_path, record) -> Path:
    path = record(tmp_path / "demo.rmb")
    (path / "hand_depth_image.rmb.mp4").unlink()
    return path


def test_missing_depth_file_is_refused_naming_it(no_hand_depth, tmp_path, hidden_entries):
    dest = tmp_path / "ds"
    with pytest.raises(RmbFormatError, match=r"camera 'hand' .* no depth images") as info:
        _convert(no_hand_depth, dest, depth=True)
    assert str(no_hand_depth / "hand_depth_image.rmb.mp4") in str(info.value)
    assert "--allow-missing-depth" in str(info.value)
    assert not dest.exists() and hidden_entries(dest.parent) == []


def test_cli_allow_missing_depth_drops_only_that_cameras_depth(
    no_hand_depth, tmp_path, capsys, caplog
):
    dest = tmp_path / "ds"
    base = ["to-lerobot", str(no_hand_depth), "--output", str(dest), "--video-codec", "h264"]
    assert main([*base, "--depth"]) == 2
    assert "hand_depth_image.rmb.mp4" in capsys.readouterr().err
    with caplog.at_level(logging.WARNING):
        assert main([*base, "--depth", "--allow-missing-depth"]) == 0
    assert "camera 'hand' has no depth images" in caplog.text
    meta = LeRobotDatasetMetadata("local/ds", root=dest)
    assert meta.depth_keys == [N.depth_image_key("front")]
    assert N.image_key("hand") in meta.video_keys


def test_without_depth_a_missing_depth_file_does_not_matter(no_hand_depth, tmp_path):
    from rmb_lerobot.converters.plan import plan_conversion

    plan = plan_conversion([no_hand_depth], ConvertOptions())
    assert plan.allow_missing_depth and plan.schema.depth_cameras == ()


def test_nan_depth_is_refused_with_frame_and_pixel_count(tmp_path, record, hidden_entries):
    path = record(tmp_path / "demo.hdf5")
    with h5py.File(path, "a") as h5:
        depth = h5["front_depth_image"][()]
        depth[4, :2, :3] = np.inf
        del h5["front_depth_image"]
        h5.create_dataset("front_depth_image", data=depth)
    dest = tmp_path / "ds"
    with pytest.raises(RmbFormatError, match="depth frame 4 holds 6 non-finite pixels") as info:
        _convert(path, dest, depth=True)
    assert "front_depth_image" in str(info.value) and str(path) in str(info.value)
    assert not dest.exists() and hidden_entries(dest.parent) == []
