"""Edit an episode's HDF5 file atomically: change a copy, then swap it in.

RMB's own tools (RefineRmbData, AddPointCloudToRmbData) open the file ``r+`` and edit it in
place, so an interruption or an error half-way leaves a damaged episode. Here the edits go to a
hidden copy beside the file (:class:`~rmb_lerobot.staging.Staging`) that replaces the original
with an atomic exchange only when every edit succeeded: readers see the old file or the new
one, and a failure leaves the episode untouched. For a compact episode only
``main.rmb.hdf5`` is copied (the videos stay where they are); a single-file episode is copied
whole, images included.
"""

from __future__ import annotations

import contextlib
import shutil
from collections.abc import Iterable, Iterator
from pathlib import Path

import h5py

from rmb_lerobot.episode.layout import episode_format
from rmb_lerobot.errors import RmbFormatError
from rmb_lerobot.staging import Staging


def hdf5_of(episode: str | Path) -> Path:
    """The HDF5 file holding an episode's keys and attributes (``main.rmb.hdf5`` or itself)."""
    episode = Path(episode)
    return episode_format(episode).hdf5_path(episode)


@contextlib.contextmanager
def edit_hdf5(episode: str | Path, *, drop: Iterable[str] = ()) -> Iterator[h5py.File]:
    """Yield a writable copy of ``episode``'s HDF5 file; it replaces the original on success.

    ``drop`` names datasets left out of the copy (to be written anew): h5py cannot reclaim
    the space of a deleted dataset, so they are never copied rather than deleted. Without
    ``drop`` the file is copied byte for byte.
    """
    target = hdf5_of(episode)
    if not target.is_file():
        raise RmbFormatError("episode not found", path=target)
    drop = set(drop)
    with Staging(target) as staging:
        if drop:
            _copy_without(target, staging.path, drop)
        else:
            shutil.copyfile(target, staging.path)
        with h5py.File(staging.path, "r+") as h5:
            yield h5
        staging.commit(overwrite=True)


def _copy_without(src: Path, dst: Path, drop: set[str]) -> None:
    with h5py.File(src, "r") as old, h5py.File(dst, "w") as new:
        for name in old:
            if name not in drop:
                old.copy(old[name], new, name=name)
        for name in old.attrs:  # with the stored dtype (fixed or variable-length strings)
            new.attrs.create(name, old.attrs[name], dtype=old.attrs.get_id(name).dtype)
