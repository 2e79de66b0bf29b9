"""Every shell and Python block in README.md and docs/*.md runs here, or says why it cannot.

A fenced block in one of :data:`CHECKED` languages must follow an HTML comment (the last
non-blank line before the fence; invisible on GitHub and on the docs site):

- ``<!-- run -->``: run, the page's blocks in order in one temporary directory;
- ``<!-- run; sub: OLD => NEW; sub: ... -->``: run after replacing text (a small size);
- ``<!-- not-run: REASON -->``: shown only, for the reason given (hardware, GPU, network, hours).

``<!-- file: NAME -->`` before a block of any language writes it to ``NAME`` in the page's
directory before the page's blocks run. docs/development.md describes the convention.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PAGES = sorted([ROOT / "README.md", *(ROOT / "docs").rglob("*.md")])
CHECKED = {"bash", "sh", "shell", "console", "python", "py", "python3", "pycon"}
PYTHON = {"python", "py", "python3"}
FENCE = re.compile(r"^(?P<indent> *)(?P<fence>`{3,}|~{3,})(?P<info>.*)$")
MARKER = re.compile(r"^<!--\s*(?P<body>.*?)\s*-->$")
BLOCK_TIMEOUT_S = 600  # one block; the page test has its own limit (900 s) below


@dataclass
class Block:
    """One fenced code block of a page."""

    page: Path
    line: int  # 1-based line of the opening fence
    language: str
    code: str
    marker: str | None  # the comment's text before the block, if any
    subs: list[tuple[str, str]] = field(default_factory=list)

    @property
    def where(self) -> str:
        return f"{self.page.relative_to(ROOT)}:{self.line}"

    @property
    def kind(self) -> str | None:
        """``run``, ``not-run``, ``file`` or None (no recognised marker)."""
        if self.marker is None:
            return None
        head = re.split(r"[;:]", self.marker, maxsplit=1)[0].strip()
        return head if head in ("run", "not-run", "file") else None


def parse(page: Path) -> list[Block]:
    """The fenced blocks of a markdown page, with the marker comment before each."""
    lines = page.read_text().splitlines()
    blocks: list[Block] = []
    i = 0
    while i < len(lines):
        match = FENCE.match(lines[i])
        if not match:
            i += 1
            continue
        fence, indent = match["fence"], len(match["indent"])
        info = match["info"].strip()
        body: list[str] = []
        j = i + 1
        while j < len(lines) and not lines[j].strip().startswith(fence):
            body.append(lines[j][indent:] if lines[j][:indent].isspace() else lines[j])
            j += 1
        previous = next((lines[k].strip() for k in range(i - 1, -1, -1) if lines[k].strip()), "")
        marker = MARKER.match(previous)
        language = info.split()[0].lower() if info else ""
        blocks.append(
            Block(page, i + 1, language, "\n".join(body) + "\n", marker["body"] if marker else None)
        )
        i = j + 1
    for block in blocks:
        if block.kind == "run":
            for part in block.marker.split(";")[1:]:
                key, _, value = part.strip().partition(":")
                assert key.strip() == "sub" and "=>" in value, f"{block.where}: bad {part!r}"
                old, new = (s.strip() for s in value.split("=>", 1))
                block.subs.append((old, new))
    return blocks


ALL = [block for page in PAGES for block in parse(page)]


def test_every_shell_and_python_block_is_run_or_says_why_not():
    problems = []
    for block in ALL:
        if block.language not in CHECKED:
            continue
        if block.kind == "not-run":
            reason = block.marker.split(":", 1)[1].strip() if ":" in block.marker else ""
            if len(reason) < 10:
                problems.append(f"{block.where}: not-run needs a reason")
        elif block.kind != "run":
            problems.append(
                f"{block.where}: a {block.language} block needs <!-- run --> or "
                "<!-- not-run: REASON --> on the line before it (docs/development.md)"
            )
    assert not problems, "\n".join(problems)


def test_substitutions_apply():
    """A ``sub:`` whose text is not in its block would silently run the full size."""
    stale = [
        f"{block.where}: {old!r}"
        for block in ALL
        if block.kind == "run"
        for old, _ in block.subs
        if old not in block.code
    ]
    assert not stale, "substitutions whose text is not in the block:\n" + "\n".join(stale)


RUN_PAGES = sorted({block.page for block in ALL if block.kind == "run"})


def environment(tmp_path: Path) -> dict[str, str]:
    """The venv's commands first, offline, caches inside ``tmp_path``, one thread each."""
    env = dict(os.environ)
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    env.update(
        REPO=str(ROOT),
        HOME=str(tmp_path / "home"),
        HF_HOME=str(tmp_path / "hf"),
        HF_LEROBOT_HOME=str(tmp_path / "hf" / "lerobot"),
        HF_HUB_OFFLINE="1",
        HF_DATASETS_OFFLINE="1",
        WANDB_MODE="disabled",
        OMP_NUM_THREADS="1",
        MUJOCO_GL=env.get("MUJOCO_GL", "egl"),
    )
    env["PYOPENGL_PLATFORM"] = env.get("PYOPENGL_PLATFORM", env["MUJOCO_GL"])
    return env


# A page's blocks run in sequence (a few CLI starts of about 10-25 CPU seconds each, LeRobot's
# import being most of it); generous for a loaded 2-core machine.
@pytest.mark.timeout(900)
@pytest.mark.parametrize("page", RUN_PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_page_blocks_run(page, tmp_path):
    work = tmp_path / "work"
    work.mkdir()
    env = environment(tmp_path)
    blocks = [block for block in ALL if block.page == page]
    for block in blocks:
        if block.kind == "file":
            (work / block.marker.split(":", 1)[1].strip()).write_text(block.code)
    for block in blocks:
        if block.kind != "run":
            continue
        code = block.code
        for old, new in block.subs:
            code = code.replace(old, new)
        if block.language in PYTHON:
            command = [sys.executable, "-c", code]
        else:
            command = ["bash", "-euo", "pipefail", "-c", code]
        try:
            result = subprocess.run(
                command,
                cwd=work,
                env=env,
                capture_output=True,
                text=True,
                timeout=BLOCK_TIMEOUT_S,
            )
        except subprocess.TimeoutExpired as error:
            pytest.fail(f"{block.where}: still running after {BLOCK_TIMEOUT_S} s\n{error.stderr}")
        assert result.returncode == 0, (
            f"{block.where} exited {result.returncode}:\n{code}\n"
            f"--- stdout ---\n{result.stdout[-3000:]}\n--- stderr ---\n{result.stderr[-5000:]}"
        )
