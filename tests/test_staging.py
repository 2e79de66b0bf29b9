"""Hidden temporaries: moved into place whole, removed on failure, stale ones cleaned up."""

from __future__ import annotations

import json
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


# Checks DEST in a tight loop (and reads DEST/version now and then) until STOP exists; prints
# how often DEST was missing.
WATCH = """
import json, os, sys
dest, stop = sys.argv[1], sys.argv[2]
checks, missing, seen = 0, 0, set()
print("ready", flush=True)
while not os.path.exists(stop):
    for _ in range(500):
        checks += 1
        try:
            os.stat(dest)
        except FileNotFoundError:
            missing += 1
    try:
        with open(os.path.join(dest, "version")) as f:
            seen.add(f.read())
    except FileNotFoundError:
        missing += 1
print(json.dumps({"checks": checks, "missing": missing, "seen": len(seen)}))
"""


def _exchange_supported(directory) -> bool:
    """Whether this OS and filesystem swap two paths atomically (independently of the package):
    Linux renameat2(RENAME_EXCHANGE), macOS renamex_np(RENAME_SWAP)."""
    import ctypes
    import ctypes.util

    a, b = directory / "probe_a", directory / "probe_b"
    a.mkdir()
    b.mkdir()
    libc = ctypes.CDLL(ctypes.util.find_library("c"), use_errno=True)
    try:
        if hasattr(libc, "renameat2"):
            return libc.renameat2(-100, os.fsencode(a), -100, os.fsencode(b), 2) == 0
        if hasattr(libc, "renamex_np"):
            return libc.renamex_np(os.fsencode(a), os.fsencode(b), 2) == 0
        return False
    finally:
        a.rmdir()
        b.rmdir()


def test_overwrite_never_leaves_the_destination_missing_for_a_reader(tmp_path):
    """``--overwrite`` (``staged_output(dest, overwrite=True)``, as the converters use it): a
    second process checking DEST all along 1000 replacements never finds it missing."""
    from rmb_lerobot.converters.atomic import staged_output

    if not _exchange_supported(tmp_path):
        pytest.skip("no atomic exchange here: the documented fallback has a short window")
    dest, stop = tmp_path / "out" / "data", tmp_path / "stop"
    dest.mkdir(parents=True)
    (dest / "version").write_text("0")
    watcher = subprocess.Popen(
        [sys.executable, "-c", WATCH, str(dest), str(stop)], stdout=subprocess.PIPE, text=True
    )
    try:
        assert watcher.stdout.readline().strip() == "ready"
        for version in range(1, 1001):
            with staged_output(dest, overwrite=True) as stage:
                stage.path.mkdir()
                (stage.path / "version").write_text(str(version))
    finally:
        stop.touch()
        out, _ = watcher.communicate(timeout=60)
    report = json.loads(out)
    assert report["missing"] == 0, (
        f"{report['missing']} of {report['checks']} checks found no {dest}"
    )
    assert report["seen"] > 1, report  # the reader ran during the replacements
    assert (dest / "version").read_text() == "1000"
    assert _entries(dest.parent) == ["data"]


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
