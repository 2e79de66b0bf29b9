"""Hidden temporaries: moved into place whole, removed on failure, stale ones cleaned up."""

from __future__ import annotations

import os
import subprocess
import sys
import time

import pytest

from rmb_lerobot import staging
from rmb_lerobot.staging import Staging, remove_stale

HOLD = """
import sys, time
from rmb_lerobot.staging import Staging
s = Staging(sys.argv[1])
s.path.mkdir()
(s.path / "part").write_text("half")
s.sibling(".shards").mkdir()
print("ready", flush=True)
time.sleep(60)
"""


def _entries(directory):
    return sorted(p.name for p in directory.iterdir())


def _hold_in_another_process(dest):
    child = subprocess.Popen(
        [sys.executable, "-c", HOLD, str(dest)], stdout=subprocess.PIPE, text=True
    )
    assert child.stdout.readline().strip() == "ready"
    return child


def test_a_committed_tree_appears_whole_and_nothing_hidden_stays(tmp_path):
    with Staging(tmp_path / "data") as stage:
        stage.path.mkdir()
        (stage.path / "a.txt").write_text("new")
        stage.sibling(".scratch").mkdir()
        assert not (tmp_path / "data").exists()
        stage.commit()
    assert _entries(tmp_path) == ["data"]
    assert (tmp_path / "data" / "a.txt").read_text() == "new"


def test_an_exception_leaves_nothing(tmp_path):
    with pytest.raises(RuntimeError), Staging(tmp_path / "data") as stage:
        stage.path.mkdir()
        raise RuntimeError("writer failed")
    assert _entries(tmp_path) == []


def test_overwrite_exchanges_atomically_and_refuses_without_permission(tmp_path):
    (tmp_path / "data").mkdir()
    (tmp_path / "data" / "old.txt").write_text("old")
    with Staging(tmp_path / "data") as stage:
        stage.path.mkdir()
        (stage.path / "new.txt").write_text("new")
        with pytest.raises(FileExistsError, match="--overwrite"):
            stage.commit(overwrite=False)
        assert _entries(tmp_path / "data") == ["old.txt"]
        stage.commit(overwrite=True)
    assert _entries(tmp_path) == ["data"]
    assert _entries(tmp_path / "data") == ["new.txt"]


def test_a_single_file_destination(tmp_path):
    with Staging(tmp_path / "episode.hdf5") as stage:
        stage.path.write_bytes(b"hdf5")
        stage.commit()
    assert _entries(tmp_path) == ["episode.hdf5"]


def test_stale_temporaries_of_a_killed_process_go_and_a_live_ones_stay(tmp_path):
    killed = _hold_in_another_process(tmp_path / "a")
    live = _hold_in_another_process(tmp_path / "b")
    try:
        killed.kill()
        killed.wait()
        removed = {p.name.split(".tmp-")[0] for p in remove_stale(tmp_path)}
        assert removed == {".a"}
        names = _entries(tmp_path)
        assert not any(n.startswith(".a.") for n in names)
        assert sum(n.startswith(".b.tmp-") for n in names) == 3  # temp, .shards, .lock
    finally:
        live.kill()
        live.wait()
    remove_stale(tmp_path)
    assert _entries(tmp_path) == []


def test_our_own_live_temporary_is_not_stale(tmp_path):
    with Staging(tmp_path / "data") as stage:
        stage.path.mkdir()
        assert remove_stale(tmp_path) == []
        assert stage.path.is_dir()


def test_a_lock_file_left_under_its_private_name_goes_once_old(tmp_path):
    private = tmp_path / ".data.tmp-0123456789ab.lock.4242-abcdef"
    private.write_text("pid 4242\n")
    assert remove_stale(tmp_path) == []  # might be a creator about to lock it
    old = time.time() - 2 * staging.PRIVATE_LOCK_GRACE_S
    os.utime(private, (old, old))
    assert remove_stale(tmp_path) == [private]
    assert _entries(tmp_path) == []


def test_what_cannot_be_removed_keeps_its_lock_for_a_later_clean_up(tmp_path, monkeypatch):
    stage = Staging(tmp_path / "data")
    stage.path.mkdir()
    monkeypatch.setattr(staging, "_remove", lambda path: False)
    stage.discard()
    assert stage.lock_path.exists()  # unlocked now: the next remove_stale retries
    monkeypatch.undo()
    remove_stale(tmp_path)
    assert _entries(tmp_path) == []
