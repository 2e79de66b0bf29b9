"""rmb-data refine: set task_desc, never half-way, never over an existing value unasked."""

import h5py
import pytest

from rmb_lerobot import keys as K
from rmb_lerobot import open_episode
from rmb_lerobot.data.edit import edit_hdf5
from rmb_lerobot.data.refine import refine_task_desc
from rmb_lerobot.errors import RmbFormatError


def _task(path):
    with open_episode(path) as ep:
        return ep.attrs[K.ATTR_TASK_DESC]


def _snapshot(directory):
    """Every file under ``directory`` with its bytes (hidden temporaries included)."""
    return {p.relative_to(directory): p.read_bytes() for p in directory.rglob("*") if p.is_file()}


def test_sets_an_empty_task_description_keeping_everything_else(tmp_path, record, attrs):
    path = record(tmp_path / "ep.rmb")
    with h5py.File(path / K.COMPACT_MAIN_FILE, "r+") as h5:
        h5.attrs[K.ATTR_TASK_DESC] = ""
    videos = {p.name: p.read_bytes() for p in path.glob("*.mp4")}
    with open_episode(path) as ep:
        before = {k: ep[k][:] for k in ep if not K.is_image_key(k)}
    [result] = refine_task_desc([tmp_path], "Insert the peg.", progress=False)
    assert result.changed and result.old == "" and _task(path) == "Insert the peg."
    assert {p.name: p.read_bytes() for p in path.glob("*.mp4")} == videos
    with open_episode(path) as ep:
        assert ep.attrs[K.ATTR_ENV] == attrs[K.ATTR_ENV]
        for key, values in before.items():
            assert (ep[key][:] == values).all(), key
        ep.validate()
    assert sorted(p.name for p in tmp_path.rglob(".*")) == []  # no temporaries left


def test_refuses_existing_values_without_changing_any_file(tmp_path, record):
    a = record(tmp_path / "a.hdf5")
    b = record(tmp_path / "b.rmb")
    with h5py.File(a, "r+") as h5:
        h5.attrs[K.ATTR_TASK_DESC] = ""  # this one alone could be set
    before = _snapshot(tmp_path)
    with pytest.raises(RmbFormatError, match="already have a different task_desc") as info:
        refine_task_desc([a, b], "Open the door.", progress=False)
    assert "b.rmb: 'Reach and close" in str(info.value) and "--overwrite" in str(info.value)
    assert _snapshot(tmp_path) == before
    results = refine_task_desc([a, b], "Open the door.", overwrite=True, progress=False)
    assert [r.changed for r in results] == [True, True]
    assert _task(a) == _task(b) == "Open the door."


def test_the_same_value_again_changes_nothing(tmp_path, record):
    path = record(tmp_path / "ep.hdf5")
    value = _task(path)
    before = _snapshot(tmp_path)
    [result] = refine_task_desc([path], value, progress=False)
    assert not result.changed and _snapshot(tmp_path) == before


def test_an_edit_that_fails_leaves_the_file_untouched(tmp_path, record):
    path = record(tmp_path / "ep.hdf5")
    before = _snapshot(tmp_path)
    with pytest.raises(RuntimeError, match="disk full"), edit_hdf5(path) as h5:
        h5.attrs[K.ATTR_TASK_DESC] = "half-way"
        raise RuntimeError("disk full")
    assert _snapshot(tmp_path) == before


def test_bad_input_is_named(tmp_path, record):
    with pytest.raises(RmbFormatError, match="episode not found"):
        refine_task_desc([tmp_path / "missing.rmb"], "x", progress=False)
    with pytest.raises(RmbFormatError, match="no episodes"):
        refine_task_desc([tmp_path], "x", progress=False)
    with pytest.raises(ValueError, match="empty"):
        refine_task_desc([record(tmp_path / "ep.hdf5")], "  ", progress=False)
