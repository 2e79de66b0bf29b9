"""MkDocs hook: serve files that live outside docs/ without copying them into the repository.

MkDocs only publishes what is under ``docs_dir``. The benchmark results (``benchmarks/RESULTS.md``
and the plots under ``benchmarks/results/``) stay where the benchmarks write them; this hook adds
them to the site at the same relative paths (``benchmarks/RESULTS.md`` ->
``/benchmarks/RESULTS/``), so the pages link to them and RESULTS.md's own relative links to its
plots resolve. The notebooks in ``examples/`` are mounted by mkdocs-jupyter (``notebook_dirs``).

It also gives mkdocstrings the package as it installs: ``rmb_lerobot.envs``,
``rmb_lerobot.converters`` and ``rmb_lerobot.policies_extra`` live in ``envs/``, ``converters/`` and
``policies_extra/`` (pyproject's package-dir mapping), which griffe's static loader does not follow.
A temporary tree of symbolic links (``rmb_lerobot/<entry>`` -> the real files, plus those three)
is put first on the Python handler's search path; nothing is imported.
"""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

from mkdocs.plugins import event_priority
from mkdocs.structure.files import File, Files

ROOT = Path(__file__).resolve().parents[1]
# (directory under the repository root, glob) pairs published at the same relative path.
MOUNTS = [
    ("benchmarks", "RESULTS.md"),
    ("benchmarks/results", "**/*.png"),
    ("benchmarks/results", "*/benchmark.md"),
]
# Links to a results directory (fine on GitHub) point at the report it holds on the site.
DIRECTORY_LINKS = {"](results/grid_small/)": "](results/grid_small/benchmark.md)"}
# Sub-packages installed from directories outside rmb_lerobot/ (pyproject: package-dir).
MAPPED = {"envs": "envs", "converters": "converters", "policies_extra": "policies_extra"}
_tree: Path | None = None


def _package_tree() -> Path:
    """A directory holding ``rmb_lerobot`` laid out as it installs (symbolic links only)."""
    global _tree
    if _tree is None:
        _tree = Path(tempfile.mkdtemp(prefix="rmb-docs-src-"))
        package = _tree / "rmb_lerobot"
        package.mkdir()
        for entry in (ROOT / "rmb_lerobot").iterdir():
            if entry.name != "__pycache__":
                (package / entry.name).symlink_to(entry)
        for name, source in MAPPED.items():
            (package / name).symlink_to(ROOT / source)
    return _tree


@event_priority(100)
def on_config(config):
    """Point mkdocstrings' Python handler at the installed layout of the package."""
    python = config["plugins"]["mkdocstrings"].config["handlers"].setdefault("python", {})
    python["paths"] = [str(_package_tree()), str(ROOT)]
    return config


def on_page_markdown(markdown: str, page, config, files) -> str:
    """Rewrite RESULTS.md's links to result directories into links to their reports."""
    if page.file.src_uri == "benchmarks/RESULTS.md":
        for old, new in DIRECTORY_LINKS.items():
            markdown = markdown.replace(old, new)
    return markdown


def on_shutdown() -> None:
    """Remove the temporary tree."""
    global _tree
    if _tree is not None:
        shutil.rmtree(_tree, ignore_errors=True)
        _tree = None


@event_priority(100)  # before the plugins, so they see these files like any other
def on_files(files: Files, config) -> Files:
    """Add the benchmark results to the site's files."""
    for directory, pattern in MOUNTS:
        for path in sorted((ROOT / directory).glob(pattern)):
            rel = path.relative_to(ROOT).as_posix()
            if files.get_file_from_path(rel) is None:
                files.append(File(rel, str(ROOT), config["site_dir"], config["use_directory_urls"]))
    return files
