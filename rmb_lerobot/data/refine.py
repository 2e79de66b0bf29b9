"""Set the task description of episodes (RMB's RefineRmbData), atomically per file.

Like the original, only the ``task_desc`` attribute changes, and an existing non-empty value is
kept unless ``overwrite`` is given. Unlike it, every episode is checked before any is changed (a
refusal in the tenth file no longer leaves nine changed and the rest not), and each file is
rewritten through :func:`rmb_lerobot.data.edit.edit_hdf5` (a failure leaves it untouched).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

from tqdm import tqdm

from rmb_lerobot import keys as K
from rmb_lerobot.data.edit import edit_hdf5, hdf5_of
from rmb_lerobot.episode import find_episodes, open_episode
from rmb_lerobot.episode.validate import read_attrs
from rmb_lerobot.errors import RmbFormatError


@dataclass(frozen=True)
class Refined:
    """What happened to one episode."""

    path: Path
    old: str
    new: str

    @property
    def changed(self) -> bool:
        return self.old != self.new


def _task_desc(path: Path) -> str:
    with open_episode(path) as episode:  # also checks the episode is readable
        value = episode.attrs.get(K.ATTR_TASK_DESC, "")
    return value if isinstance(value, str) else str(value)


def refine_task_desc(
    sources: Iterable[str | Path],
    task_desc: str,
    *,
    overwrite: bool = False,
    progress: bool = True,
) -> list[Refined]:
    """Set ``task_desc`` in every episode of ``sources`` (episodes or directories of them).

    Raises :class:`RmbFormatError` before changing anything when an episode cannot be read or
    already holds a different non-empty description and ``overwrite`` is false (the message
    names every such file and its value). Episodes that already hold ``task_desc`` are left
    alone.
    """
    if not task_desc.strip():
        raise ValueError("--task-desc is empty; give the task in words, e.g. 'Insert the peg.'")
    episodes = find_episodes(*sources)
    if not episodes:
        raise RmbFormatError("no episodes (*.rmb, *.hdf5) found", path=", ".join(map(str, sources)))
    plan = [Refined(path, _task_desc(path), task_desc) for path in episodes]
    conflicts = [r for r in plan if r.changed and r.old and not overwrite]
    if conflicts:
        listed = "; ".join(f"{r.path}: {r.old!r}" for r in conflicts[:5])
        more = f" (and {len(conflicts) - 5} more)" if len(conflicts) > 5 else ""
        raise RmbFormatError(
            f"{len(conflicts)} episode(s) already have a different task_desc, nothing was "
            f"changed: {listed}{more}; pass --overwrite to replace it",
            path=conflicts[0].path,
            key=K.ATTR_TASK_DESC,
        )
    for refined in tqdm(plan, desc="refine", unit="episode", disable=not progress):
        if not refined.changed:
            continue
        with edit_hdf5(refined.path) as h5:
            now = read_attrs(h5, hdf5_of(refined.path)).get(K.ATTR_TASK_DESC, "")
            if now != refined.old:  # changed by someone else since we looked
                raise RmbFormatError(
                    f"task_desc changed while refining (was {refined.old!r}, now {now!r}); "
                    "not overwriting",
                    path=refined.path,
                    key=K.ATTR_TASK_DESC,
                )
            h5.attrs[K.ATTR_TASK_DESC] = task_desc
    return plan
