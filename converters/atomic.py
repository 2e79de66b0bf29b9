"""Write a directory tree next to its destination and move it into place only when complete.

A conversion that fails, is interrupted (Ctrl-C, SIGTERM through ``SystemExit``) or crashes
leaves nothing at the destination: the work happens in a hidden sibling (same filesystem, so the
final move is an atomic rename) that is removed on error.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import uuid
from collections.abc import Iterator
from pathlib import Path


def check_destination(dest: Path, overwrite: bool) -> None:
    """Fail early, before any work, if ``dest`` exists and may not be replaced."""
    if dest.exists() and not overwrite:
        raise FileExistsError(f"destination exists: {str(dest)!r} (pass --overwrite to replace it)")


@contextlib.contextmanager
def staged_directory(dest: str | Path, overwrite: bool = False) -> Iterator[Path]:
    """Yield a not-yet-existing sibling path to build ``dest`` in; move it into place on success.

    With ``overwrite`` an existing ``dest`` is swapped out only after the new tree is complete,
    so ``dest`` never holds a partial result.
    """
    dest = Path(dest)
    check_destination(dest, overwrite)
    dest.parent.mkdir(parents=True, exist_ok=True)
    tmp = dest.with_name(f".{dest.name}.tmp-{uuid.uuid4().hex[:8]}")
    try:
        yield tmp
        if not tmp.is_dir():
            raise FileNotFoundError(f"nothing was written to {str(tmp)!r}")
        _move_into_place(tmp, dest, overwrite)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def _move_into_place(tmp: Path, dest: Path, overwrite: bool) -> None:
    if not dest.exists():
        os.replace(tmp, dest)
        return
    check_destination(dest, overwrite)  # appeared while we worked
    trash = dest.with_name(f".{dest.name}.old-{uuid.uuid4().hex[:8]}")
    os.replace(dest, trash)
    os.replace(tmp, dest)
    if trash.is_dir():
        shutil.rmtree(trash, ignore_errors=True)
    else:
        trash.unlink(missing_ok=True)
