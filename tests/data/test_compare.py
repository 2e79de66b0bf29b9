"""rmb-data compare: per-key differences against tolerances, with a verdict."""

import math
import shutil

import h5py
import numpy as np
import pytest

from rmb_lerobot import keys as K
from rmb_lerobot.data.compare import (
    Tolerances,
    _depth_diff_mm,
    compare_episodes,
    format_comparison,
)
from rmb_lerobot.episode import switch_format


def _rows(result):
    return {row.key: row for row in result.rows}


def test_identical_episodes_have_no_difference(tmp_path, record):
    a = record(tmp_path / "a.hdf5")
    shutil.copy(a, tmp_path / "b.hdf5")
    result = compare_episodes(a, tmp_path / "b.hdf5", progress=False)
    assert result.ok and not result.failures
    rows = _rows(result)
    assert rows["front_rgb_image"].measure == "PSNR dB" and math.isinf(
        rows["front_rgb_image"].value
    )
    assert rows["front_depth_image"].value == 0 and rows[K.MEASURED_JOINT_POS].value == 0
    assert "within tolerances" in format_comparison(result)


def test_compact_against_single_file_is_within_codec_tolerances(tmp_path, record):
    """The compact variant's lossy RGB and mm depth, measured the way each deserves."""
    a = record(tmp_path / "a.hdf5")
    b = switch_format(a, tmp_path / "a.rmb")
    result = compare_episodes(a, b, progress=False)
    rows = _rows(result)
    assert result.ok, format_comparison(result)
    assert 30 < rows["front_rgb_image"].value < math.inf
    assert 0 < rows["hand_depth_image"].value <= 0.5  # rounding to mm
    assert rows[K.TIME].value == 0
    assert not any(row.key == "attr format" for row in result.rows)  # the variant may differ
    strict = compare_episodes(a, b, Tolerances(min_psnr=80), progress=False)
    assert [row.key for row in strict.failures] == ["front_rgb_image", "hand_rgb_image"]


def test_a_changed_value_fails_with_its_size(tmp_path, record):
    a = record(tmp_path / "a.hdf5")
    b = shutil.copy(a, tmp_path / "b.hdf5")
    with h5py.File(b, "r+") as h5:
        h5[K.MEASURED_EEF_WRENCH][5, 2] += 0.01
        h5.attrs[K.ATTR_TASK_DESC] = "Something else."
    result = compare_episodes(a, b, progress=False)
    failed = {row.key: row for row in result.failures}
    assert set(failed) == {K.MEASURED_EEF_WRENCH, "attr task_desc"}
    assert failed[K.MEASURED_EEF_WRENCH].value == pytest.approx(0.01)
    assert "Something else." in failed["attr task_desc"].detail
    loose = compare_episodes(a, b, Tolerances(atol=0.1), ignore_attrs=("format", "task_desc"))
    assert loose.ok


def test_missing_keys_and_length_mismatch_are_failures(tmp_path, record, record_with):
    a = record(tmp_path / "a.hdf5")
    b = record_with(
        tmp_path / "b.hdf5", num_steps=10, extra=lambda i: {"left_tactile_sensor": np.zeros((5, 8))}
    )
    with h5py.File(b, "r+") as h5:
        del h5["hand_rgb_image"]
        h5.attrs[K.ATTR_CAMERA_NAMES] = ["front"]
    result = compare_episodes(a, b, progress=False)
    failed = {row.key: row for row in result.failures}
    assert failed["(steps)"].detail == "A has 12 steps, B 10; comparing the first 10"
    assert failed["hand_rgb_image"].measure == "missing in B"
    assert failed["left_tactile_sensor"].measure == "missing in A"
    assert failed["attr camera_names"].measure == "differs"
    assert _rows(result)[K.MEASURED_JOINT_POS].ok  # the common steps agree
    table = format_comparison(result, only_failures=True)
    assert "FAIL" in table and "ok" not in table.split("\n", 3)[3]


def test_depth_without_data_compares_equal_whatever_its_value():
    a = np.array([[np.nan, 0.0, 1.0, 1.0]], np.float32)
    b = np.array([[0.0, -1.0, 1.0004, np.inf]], np.float32)
    diff = _depth_diff_mm(a, b)
    assert diff[0, 0] == 0 and diff[0, 1] == 0  # no data either way
    assert diff[0, 2] == pytest.approx(0.4, abs=1e-3)
    assert np.isinf(diff[0, 3])  # data in A only


def test_shape_mismatch_is_reported(tmp_path, steps, attrs):
    from rmb_lerobot import EpisodeWriter

    paths = []
    for name, size in (("a.hdf5", (64, 48)), ("b.hdf5", (32, 24))):
        with EpisodeWriter(tmp_path / name, {**attrs, K.ATTR_CAMERA_NAMES: ["front"]}) as writer:
            for step in steps:
                img = step["front_rgb_image"][: size[1], : size[0]]
                writer.append({K.TIME: step[K.TIME], "front_rgb_image": img})
        paths.append(tmp_path / name)
    result = compare_episodes(*paths, progress=False)
    row = _rows(result)["front_rgb_image"]
    assert not row.ok and row.measure == "shape differs" and "(12, 24, 32, 3)" in row.detail
