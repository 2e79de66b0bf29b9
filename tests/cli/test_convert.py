"""The rmb-convert command line."""

import subprocess
import sys

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
