"""Hidden temporaries beside a destination, moved into place only when complete.

Every output that takes time to write (an episode being recorded, a dataset being converted)
is built in a hidden sibling of its destination, ``.NAME.tmp-TOKEN`` (plus, if the writer
wants scratch space, more siblings starting with the same prefix, e.g. ``.NAME.tmp-TOKEN.shards``).

How a later run knows a temporary is stale: its writer holds an exclusive ``flock(2)`` on a
lock file ``.NAME.tmp-TOKEN.lock`` for as long as it works. The kernel drops that lock when the
process ends, however it ends (an exception, Ctrl-C, SIGTERM, SIGKILL, a crash), so
:func:`remove_stale` takes every lock it can get and removes what that lock guarded, while a
temporary whose lock is still held belongs to a live process (a parallel run) and is left
alone. No process ids are involved, so a reused pid or another user's run can never make a live
temporary look stale. The lock file is created and locked under a private name and only then
renamed to ``*.lock``, so no cleaner ever sees an unlocked lock file of a live writer.

Replacing an existing destination (``overwrite``) is an atomic exchange (Linux ``renameat2``
with ``RENAME_EXCHANGE``, macOS ``renamex_np`` with ``RENAME_SWAP``): readers see the old tree or
the new one, never a missing destination. Where neither call exists the old tree is first moved
aside, which leaves a short window without a destination.
"""

from __future__ import annotations

import contextlib
import ctypes
import ctypes.util
import errno
import fcntl
import logging
import os
import shutil
import sys
import time
import uuid
from pathlib import Path

logger = logging.getLogger(__name__)

TMP_MARK = ".tmp-"
LOCK_SUFFIX = ".lock"
PRIVATE_LOCK_GRACE_S = 60.0


class Staging:
    """A hidden, locked sibling of ``dest`` to build it in; :meth:`commit` moves it into place.

    ``path`` does not exist yet: the caller creates it (a file or a directory). Use as a context
    manager: leaving the block with an exception discards everything; leaving it normally
    without :meth:`commit` discards too (nothing half-written is ever left behind).
    """

    def __init__(self, dest: str | Path):
        self.dest = Path(dest)
        self.dest.parent.mkdir(parents=True, exist_ok=True)
        self.prefix = f".{self.dest.name}{TMP_MARK}{uuid.uuid4().hex[:12]}"
        self.path = self.dest.with_name(self.prefix)
        lock = self.dest.with_name(self.prefix + LOCK_SUFFIX)
        self._lock_fd, self.lock_path = _create_locked(lock)
        self.done = False

    def sibling(self, suffix: str) -> Path:
        """Scratch space owned by this staging (removed with it, and by stale clean-up)."""
        return self.dest.with_name(self.prefix + suffix)

    def commit(self, overwrite: bool = False) -> Path:
        """Move ``path`` to ``dest``; with ``overwrite`` exchange it atomically with the old one."""
        if not self.path.exists():
            raise FileNotFoundError(f"nothing was written to {str(self.path)!r}")
        if not (self.dest.exists() or self.dest.is_symlink()):
            os.replace(self.path, self.dest)
        elif not overwrite:
            raise FileExistsError(
                f"destination exists: {str(self.dest)!r} (pass --overwrite to replace it)"
            )
        else:
            replace_atomically(self.path, self.dest)  # the old tree is now at self.path
        self.done = True
        self._cleanup()
        return self.dest

    def discard(self) -> None:
        """Remove everything this staging wrote."""
        self.done = True
        self._cleanup()

    def _cleanup(self) -> None:
        left = [e for e in _owned_siblings(self.dest.parent, self.prefix) if not _remove(e)]
        if left:  # keep the lock file: once we exit, remove_stale sees them and retries
            logger.warning("could not remove %s", ", ".join(str(e) for e in left))
        else:
            with contextlib.suppress(FileNotFoundError):
                self.lock_path.unlink()  # remove before unlocking: no cleaner can race us
        if self._lock_fd is not None:
            os.close(self._lock_fd)
            self._lock_fd = None

    def __enter__(self) -> Staging:
        return self

    def __exit__(self, *exc) -> None:
        if not self.done:
            self.discard()


def remove_stale(directory: str | Path) -> list[Path]:
    """Remove temporaries in ``directory`` left by processes that ended; returns what went.

    A temporary is stale when nobody holds its lock (see the module docstring). Temporaries of
    live processes are untouched. Safe to run from several processes at once.
    """
    directory = Path(directory)
    removed: list[Path] = []
    if not directory.is_dir():
        return removed
    removed += _remove_orphan_private_locks(directory)
    for lock in sorted(directory.glob(f".*{TMP_MARK}*{LOCK_SUFFIX}")):
        try:
            fd = os.open(lock, os.O_RDWR)
        except FileNotFoundError:
            continue  # its owner finished meanwhile
        try:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                continue  # a live process works on it
            if not _same_file(fd, lock):
                continue  # removed and possibly recreated meanwhile
            prefix = lock.name.removesuffix(LOCK_SUFFIX)
            owned = _owned_siblings(directory, prefix)
            gone = [entry for entry in owned if _remove(entry)]
            removed += gone
            if len(gone) == len(owned):
                with contextlib.suppress(FileNotFoundError):
                    lock.unlink()
        finally:
            os.close(fd)
    if removed:
        logger.warning(
            "removed %d stale temporar%s left by ended processes in %s: %s",
            len(removed),
            "y" if len(removed) == 1 else "ies",
            directory,
            ", ".join(p.name for p in removed),
        )
    return removed


def _remove_orphan_private_locks(directory: Path) -> list[Path]:
    """Lock files still under their private name: their creator died between creating and
    renaming them (a signal in that instant). Unlocked and older than a minute means dead:
    a live creator holds the lock within microseconds of creating the file."""
    removed = []
    for private in directory.glob(f".*{TMP_MARK}*{LOCK_SUFFIX}.*"):
        try:
            fd = os.open(private, os.O_RDWR)
        except FileNotFoundError:
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            if time.time() - os.fstat(fd).st_mtime > PRIVATE_LOCK_GRACE_S:
                private.unlink(missing_ok=True)
                removed.append(private)
        except BlockingIOError:
            pass
        finally:
            os.close(fd)
    return removed


def replace_atomically(new: Path, dest: Path) -> None:
    """Put ``new`` at ``dest``; the old ``dest`` ends up at ``new`` (caller removes it)."""
    if _exchange(new, dest):
        return
    trash = new.with_name(new.name + ".old")
    os.replace(dest, trash)
    os.replace(new, dest)
    os.replace(trash, new)


def _create_locked(final: Path) -> tuple[int, Path]:
    """Create ``final`` already locked: lock under a private name, then rename into view."""
    private = final.with_name(final.name + f".{os.getpid()}-{uuid.uuid4().hex[:6]}")
    fd = os.open(private, os.O_RDWR | os.O_CREAT | os.O_EXCL, 0o644)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        os.write(fd, f"pid {os.getpid()}\n".encode())
        os.replace(private, final)
    except BaseException:
        os.close(fd)
        with contextlib.suppress(FileNotFoundError):
            private.unlink()
        raise
    return fd, final


def _owned_siblings(directory: Path, prefix: str) -> list[Path]:
    """The temporary and its scratch siblings (``prefix`` + anything), but not its lock."""
    return [
        entry
        for entry in directory.glob(f"{_glob_escape(prefix)}*")
        if entry.name != prefix + LOCK_SUFFIX
    ]


def _glob_escape(text: str) -> str:
    return "".join(f"[{c}]" if c in "*?[" else c for c in text)


def _same_file(fd: int, path: Path) -> bool:
    try:
        st = path.stat()
    except FileNotFoundError:
        return False
    here = os.fstat(fd)
    return (st.st_dev, st.st_ino) == (here.st_dev, here.st_ino)


def _remove(path: Path) -> bool:
    """Remove a file or tree; False if something of it is still there."""
    try:
        if path.is_dir() and not path.is_symlink():
            shutil.rmtree(path)
        else:
            path.unlink()
    except FileNotFoundError:
        pass
    except OSError as exc:
        logger.warning("cannot remove %s: %s", path, exc)
    return not (path.exists() or path.is_symlink())


def _exchange(a: Path, b: Path) -> bool:
    """Atomically swap two paths; False where the OS offers no such call."""
    libc = _libc()
    if libc is None:
        return False
    if sys.platform.startswith("linux") and hasattr(libc, "renameat2"):
        at_fdcwd, rename_exchange = -100, 2
        result = libc.renameat2(at_fdcwd, os.fsencode(a), at_fdcwd, os.fsencode(b), rename_exchange)
    elif sys.platform == "darwin" and hasattr(libc, "renamex_np"):
        rename_swap = 2
        result = libc.renamex_np(os.fsencode(a), os.fsencode(b), rename_swap)
    else:
        return False
    if result == 0:
        return True
    err = ctypes.get_errno()
    if err in (errno.ENOSYS, errno.EINVAL, errno.ENOTSUP):
        return False  # the filesystem cannot exchange: fall back
    raise OSError(err, os.strerror(err), str(b))


_LIBC: ctypes.CDLL | bool | None = False


def _libc() -> ctypes.CDLL | None:
    global _LIBC
    if _LIBC is False:
        name = ctypes.util.find_library("c")
        try:
            _LIBC = ctypes.CDLL(name, use_errno=True) if name else None
        except OSError:
            _LIBC = None
    return _LIBC  # type: ignore[return-value]
