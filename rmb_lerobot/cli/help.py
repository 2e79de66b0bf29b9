"""Help output shared by the console scripts: every option's default, shown where it has one."""

from __future__ import annotations

import argparse
from collections.abc import Iterator


class DefaultsHelpFormatter(argparse.ArgumentDefaultsHelpFormatter):
    """:class:`argparse.ArgumentDefaultsHelpFormatter` without the noise.

    Appends ``(default: ...)`` to an option's help unless the help already states its default
    (it says "default"), the option has none (``None``) or is a flag (``store_true``: off unless
    given). Lists are shown as they are typed (``front hand``), not as Python lists.
    """

    def _get_help_string(self, action: argparse.Action) -> str | None:
        help_text = action.help or ""
        default = action.default
        if (
            "default" in help_text
            or default is None
            or default is argparse.SUPPRESS
            or isinstance(default, bool)
            or not (action.option_strings or action.nargs in (argparse.OPTIONAL, "*"))
        ):
            return action.help
        if isinstance(default, list | tuple):
            if not default:
                return action.help
            shown = " ".join(str(item) for item in default)
        else:
            shown = str(default)
        return f"{help_text} (default: {shown.replace('%', '%%')})"


class RawDescriptionDefaultsHelpFormatter(
    argparse.RawDescriptionHelpFormatter, DefaultsHelpFormatter
):
    """:class:`DefaultsHelpFormatter` that keeps the description's and epilog's line breaks."""


def first_line(doc: str | None) -> str:
    """A module docstring's first line as plain text for ``--help`` (no RST ````literals````)."""
    return (doc or "").strip().splitlines()[0].replace("``", "")


def iter_parsers(parser: argparse.ArgumentParser) -> Iterator[argparse.ArgumentParser]:
    """``parser`` and every sub-command's parser under it, depth first."""
    yield parser
    for action in parser._actions:  # argparse keeps sub-commands as an action's choices
        if isinstance(action, argparse._SubParsersAction):
            for sub in dict.fromkeys(action.choices.values()):  # aliases share a parser
                yield from iter_parsers(sub)


def apply_formatter(
    parser: argparse.ArgumentParser, formatter: type[argparse.HelpFormatter]
) -> argparse.ArgumentParser:
    """Give ``parser`` and its sub-commands' parsers ``formatter`` (``add_parser`` does not
    inherit it); returns ``parser``."""
    for each in iter_parsers(parser):
        each.formatter_class = formatter
    return parser
