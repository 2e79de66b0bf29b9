"""The rmb-convert command line."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from rmb_lerobot import open_episode
from rmb_lerobot.cli.convert import main


def test_switch_format_command(tmp_path, record, capsys):
    src = record(tmp_path / "a.rmb")
    assert main(["switch-format", str(src), str(tmp_path / "a.hdf5")]) == 0
    assert "wrote" in capsys.readouterr().out
    with open_episode(tmp_path / "a.hdf5") as ep:
        assert ep.format.short_name == "hdf5" and len(ep) == 12


def test_bad_input_exits_2_with_a_message_naming_the_file(tmp_path, capsys):
    assert main(["switch-format", str(tmp_path / "missing.rmb"), str(tmp_path / "x.hdf5")]) == 2
    err = capsys.readouterr().err
    assert "episode not found" in err and "missing.rmb" in err
    assert not (tmp_path / "x.hdf5").exists()


def test_installed_console_script_runs(tmp_path):
    result = subprocess.run(
        [sys.executable, "-m", "rmb_lerobot.cli.convert", "--help"], capture_output=True, text=True
    )
    assert result.returncode == 0 and "switch-format" in result.stdout


# ------------------------------------------------------------------ interrupted conversions
@pytest.fixture
def episodes(tmp_path, record) -> Path:
    """Three small synthetic episodes (12 steps, two 64x48 cameras)."""
    for name in ("a", "b", "c"):
        record(tmp_path / "src" / f"{name}.rmb")
    return tmp_path / "src"


def _old_dataset(path: Path) -> Path:
    (path / "meta").mkdir(parents=True)
    (path / "meta" / "info.json").write_text("the old dataset")
    return path


def _hidden(directory: Path) -> list[str]:
    return sorted(p.name for p in directory.iterdir() if p.name.startswith("."))


def _signal_at_first_episode(monkeypatch, signum: int) -> None:
    """Deliver a real ``signum`` to this process once the first episode is being saved."""
    from rmb_lerobot.converters.encoder import ConversionDataset

    original = ConversionDataset.save_episode

    def save_episode(self, *args, **kwargs):
        os.kill(os.getpid(), signum)  # the handler runs in this (the main) thread, right now
        return original(self, *args, **kwargs)

    monkeypatch.setattr(ConversionDataset, "save_episode", save_episode)


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGINT])
def test_sigterm_and_ctrl_c_keep_the_old_dataset_and_leave_nothing(
    episodes, tmp_path, monkeypatch, capsys, signum
):
    dest = _old_dataset(tmp_path / "out" / "ds")
    _signal_at_first_episode(monkeypatch, signum)
    # Ctrl-C as a terminal delivers it: Python's default SIGINT handler, whatever an earlier
    # test in this (long-lived xdist) worker left installed. Once, CI saw SIGINT ignored here.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        code = main(["to-lerobot", str(episodes), "--output", str(dest), "--overwrite"])
    finally:
        signal.signal(signal.SIGINT, previous)
    assert code == 128 + signum
    err = capsys.readouterr().err
    name = signal.Signals(signum).name
    lines = [line for line in err.splitlines() if "rmb-convert:" in line]
    assert lines == [
        f"rmb-convert: interrupted ({name}); nothing was written "
        "(an existing destination is unchanged)"
    ]
    assert "Traceback" not in err
    assert (dest / "meta" / "info.json").read_text() == "the old dataset"
    assert _hidden(dest.parent) == [] and sorted(p.name for p in dest.rglob("*")) == [
        "info.json",
        "meta",
    ]


def test_allow_non_finite_reaches_both_conversions(tmp_path, monkeypatch):
    import rmb_lerobot.converters as converters

    seen = {}
    monkeypatch.setattr(converters, "to_lerobot", lambda *a, **k: seen.update(to=k) or ("r", "p"))
    monkeypatch.setattr(converters, "from_lerobot", lambda *a, **k: seen.update(back=k) or [])
    assert main(["to-lerobot", "x.rmb", "--output", "o", "--allow-non-finite"]) == 0
    assert main(["from-lerobot", "--root", "d", "--output", "o", "--allow-non-finite"]) == 0
    assert seen["to"]["options"].allow_non_finite and seen["back"]["allow_non_finite"]
    assert main(["to-lerobot", "x.rmb", "--output", "o"]) == 0
    assert not seen["to"]["options"].allow_non_finite


# rmb-convert in a fresh process that first imports the converters' modules, as any program
# using them may: the package's functions must stay functions (they once became the modules).
_RMB_CONVERT = """
import sys
import rmb_lerobot.converters.lerobot_to_rmb
import rmb_lerobot.converters.rmb_to_lerobot
from rmb_lerobot.converters import from_lerobot, to_lerobot
assert callable(to_lerobot) and callable(from_lerobot), (to_lerobot, from_lerobot)
from rmb_lerobot.cli.convert import main
sys.exit(main())
"""


def _start(episodes: Path, dest: Path, tmpdir: Path, *extra: str) -> subprocess.Popen:
    """Start the conversion; its output goes to ``dest.parent.with_suffix(".log")``."""
    env = {**os.environ, "TMPDIR": str(tmpdir), "OMP_NUM_THREADS": "1", "HF_HUB_OFFLINE": "1"}
    args = ["to-lerobot", str(episodes), "--output", str(dest), *extra]
    return subprocess.Popen(
        [sys.executable, "-c", _RMB_CONVERT, *args],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=dest.parent.with_suffix(".log").open("w"),
        start_new_session=True,  # its own process group, so the test can end all it started
    )


def _writing(dest: Path) -> bool:
    """The staging directory exists and LeRobot has begun the dataset in it."""
    return any(
        (p / "meta" / "info.json").is_file()
        for p in dest.parent.glob(f".{dest.name}.tmp-*")
        if p.suffix != ".lock"
    )


def test_sigkill_leaves_only_temporaries_the_next_run_removes(episodes, tmp_path, caplog):
    """Two real runs killed while writing (a new dataset; --overwrite of an old one): the
    destinations are as before, the leftovers are hidden, and the next runs remove them."""
    tmpdir = tmp_path / "tmpdir"
    tmpdir.mkdir()
    fresh = tmp_path / "out1" / "ds"
    old = _old_dataset(tmp_path / "out2" / "ds")
    runs = {
        fresh: _start(episodes, fresh, tmpdir),
        old: _start(episodes, old, tmpdir, "--overwrite"),
    }
    try:
        deadline = time.monotonic() + 240
        waiting = dict(runs)
        while waiting and time.monotonic() < deadline:
            for dest, process in list(waiting.items()):
                if _writing(dest):
                    process.send_signal(signal.SIGKILL)
                    del waiting[dest]
                elif process.poll() is not None:
                    log = dest.parent.with_suffix(".log").read_text()
                    pytest.fail(f"finished before it could be killed:\n{log}")
            time.sleep(0.005)
        assert not waiting, "no conversion started writing within the time limit"
        for process in runs.values():
            assert process.wait(timeout=30) == -signal.SIGKILL
    finally:
        for process in runs.values():
            if process.poll() is None:
                os.killpg(process.pid, signal.SIGKILL)

    assert not fresh.exists() and _hidden(fresh.parent)  # the staging and its lock
    assert (old / "meta" / "info.json").read_text() == "the old dataset" and _hidden(old.parent)
    # Temporary files stayed in the staging (torch keeps its compile cache in $TMPDIR).
    assert [p.name for p in tmpdir.iterdir() if not p.name.startswith("torchinductor_")] == []

    assert main(["to-lerobot", str(episodes), "--output", str(fresh)]) == 0
    assert main(["to-lerobot", str(episodes), "--output", str(old), "--overwrite"]) == 0
    removed = [r.getMessage() for r in caplog.records if "stale" in r.getMessage()]
    assert len(removed) == 2 and all(".ds.tmp-" in message for message in removed)
    for dest in (fresh, old):
        assert _hidden(dest.parent) == []
        assert (dest / "meta" / "info.json").read_text().startswith("{")
