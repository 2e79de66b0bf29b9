"""Every console script's --help: each option explained, defaults shown, plain text (issue 30).

In-process through each script's ``build_parser()`` (fast: no env, no torch import).
"""

from __future__ import annotations

import argparse
import importlib
import tomllib
from pathlib import Path

import pytest

from rmb_lerobot.cli.help import iter_parsers

PYPROJECT = Path(__file__).parents[2] / "pyproject.toml"
SCRIPTS = tomllib.loads(PYPROJECT.read_text())["project"]["scripts"]


def _parser(entry_point: str) -> argparse.ArgumentParser:
    module, _, _ = entry_point.partition(":")
    return importlib.import_module(module).build_parser()


def test_every_console_script_is_covered():
    assert set(SCRIPTS) >= {"rmb-collect", "rmb-quickstart", "rmb-benchmark", "rmb-convert"}


@pytest.mark.parametrize("script", sorted(SCRIPTS))
def test_every_option_has_help_and_its_default_is_shown(script, capsys):
    parser = _parser(SCRIPTS[script])
    undocumented = []
    for each in iter_parsers(parser):
        assert issubclass(each.formatter_class, argparse.ArgumentDefaultsHelpFormatter), each.prog
        assert "``" not in (each.description or "") + (each.epilog or ""), each.prog
        for action in each._actions:
            if isinstance(action, argparse._HelpAction | argparse._SubParsersAction):
                continue
            if not (action.help or "").strip():
                undocumented.append(f"{each.prog} {'/'.join(action.option_strings) or action.dest}")
            elif action.default not in (None, False, [], argparse.SUPPRESS):
                shown = each.formatter_class(each.prog)._get_help_string(action)
                assert "default" in shown, f"{each.prog} {action.dest}: default not shown"
        with pytest.raises(SystemExit) as info:
            each.parse_args(["--help"])
        assert info.value.code == 0
        assert capsys.readouterr().out.startswith("usage: ")
    assert undocumented == []
