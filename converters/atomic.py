"""Build a conversion's output beside its destination; move it into place only when complete.

The work happens in a :class:`~rmb_lerobot.staging.Staging` temporary (a hidden, flock'ed
sibling of the destination), so a conversion that fails, is interrupted (Ctrl-C, SIGTERM) or is
killed (SIGKILL, a crash) never leaves anything at the destination, and ``--overwrite``
exchanges the old tree for the new one atomically: the destination is never missing.

What a killed run leaves (the hidden temporary, its scratch siblings) is removed by the next
conversion into the same directory (:func:`prepare_destination`, via
:func:`~rmb_lerobot.staging.remove_stale`), which tells it from a live run's by its lock.

Temporary files of the libraries we call (LeRobot joins episode videos through ``tempfile``)
go into the staging's scratch sibling ``.tmp`` too, so a killed run leaves nothing in
``$TMPDIR`` either; see :func:`staged_output` (and :mod:`.shards` for worker processes, which
are spawned so that multiprocessing needs no ``pymp-*`` directory).

Finally, files are given the modes a plain ``open()``/``mkdir`` would (``0666``/``0777`` less the
umask): LeRobot writes videos through ``tempfile`` (mode ``0600``) and moves them into place,
which made converted datasets unreadable to the rest of a lab.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

from rmb_lerobot.staging import Staging, remove_stale

SCRATCH = ".tmp"  # the staging sibling that replaces $TMPDIR while a conversion runs


def check_destination(dest: Path, overwrite: bool) -> None:
    """Fail early, before any work, if ``dest`` exists and may not be replaced."""
    if (dest.exists() or dest.is_symlink()) and not overwrite:
        raise FileExistsError(f"destination exists: {str(dest)!r} (pass --overwrite to replace it)")


def prepare_destination(dest: str | Path, overwrite: bool) -> Path:
    """Remove what killed runs left beside ``dest``, then :func:`check_destination`."""
    dest = Path(dest)
    remove_stale(dest.parent)  # logs what it removed, as a warning
    check_destination(dest, overwrite)
    return dest


def current_umask() -> int:
    """The process umask, read without changing it where the OS allows (Linux)."""
    with contextlib.suppress(OSError, ValueError), open("/proc/self/status") as status:
        for line in status:
            if line.startswith("Umask:"):
                return int(line.split()[1], 8)
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def apply_umask(root: Path, umask: int) -> None:
    """Give every file and directory under ``root`` the mode ``open()``/``mkdir`` would."""
    file_mode, dir_mode = 0o666 & ~umask, 0o777 & ~umask
    if not root.is_dir():
        os.chmod(root, file_mode)
        return
    for directory, _, files in os.walk(root):
        os.chmod(directory, dir_mode)
        for name in files:
            path = os.path.join(directory, name)
            if not os.path.islink(path):
                os.chmod(path, file_mode)


@contextlib.contextmanager
def scratch_tempdir(path: Path) -> Iterator[Path]:
    """Make ``path`` (created here) Python's temporary directory until the block ends.

    ``tempfile.tempdir`` is process-wide: other threads of a program calling us see it too,
    for the duration of the conversion.
    """
    path.mkdir()
    previous = tempfile.tempdir
    tempfile.tempdir = str(path)
    try:
        yield path
    finally:
        tempfile.tempdir = previous


@contextlib.contextmanager
def staged_output(dest: str | Path, overwrite: bool = False) -> Iterator[Staging]:
    """A :class:`Staging` for ``dest`` to build ``staging.path`` in; committed on success.

    Inside the block, temporary files go to ``staging.sibling(".tmp")``. On success the modes
    are set from the umask (:func:`apply_umask`) and the tree is moved into place (an atomic
    exchange with ``overwrite``); on any exception everything is removed.
    """
    umask = current_umask()
    with Staging(dest) as staging:
        with scratch_tempdir(staging.sibling(SCRATCH)):
            yield staging
        if not staging.path.exists():
            raise FileNotFoundError(f"nothing was written to {str(staging.path)!r}")
        apply_umask(staging.path, umask)
        staging.commit(overwrite)
