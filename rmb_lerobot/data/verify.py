"""``rmb-data verify``: read everything of RMB episodes and converted LeRobot datasets, report
every problem.

Where opening an episode checks only its header and a read only what is read, verify reads
every byte: every HDF5 dataset in full (HDF5 verifies the Fletcher-32 checksums this package
writes), every video frame, every parquet file, and the SHA-256 of every video whose digest the
writer recorded. RMB episodes: :mod:`.verify_rmb`; LeRobot datasets: :mod:`.verify_lerobot`.
What cannot be found: a changed value in a file without checksums (any HDF5 file of the original
RMB, its videos, LeRobot's videos) that still decodes to a valid value or frame.
"""

from __future__ import annotations

import time
from collections.abc import Iterable, Sequence
from pathlib import Path

from tqdm import tqdm

from rmb_lerobot import keys as K
from rmb_lerobot.data.verify_lerobot import is_lerobot_dataset, verify_dataset
from rmb_lerobot.data.verify_report import Finding, Report, format_table
from rmb_lerobot.data.verify_rmb import verify_episode
from rmb_lerobot.episode.reader import find_episodes
from rmb_lerobot.errors import RmbFormatError

__all__ = ["Finding", "Report", "expand_paths", "format_table", "verify_paths"]


def expand_paths(paths: Iterable[str | Path]) -> list[tuple[Path, str]]:
    """``(path, kind)`` for every episode and dataset to verify.

    A LeRobot dataset root (it has ``meta/info.json``) is one item; a directory otherwise
    contributes its episodes (RMB's scan: ``*.rmb`` and ``*.hdf5``) and the LeRobot datasets
    directly inside it.

    Args:
        paths: Episodes, dataset roots, or directories holding them.

    Returns:
        Items with kind ``rmb``, ``hdf5`` or ``lerobot``.

    Raises:
        RmbFormatError: A path is none of these (the message names it).
    """
    items: list[tuple[Path, str]] = []
    for path in map(Path, paths):
        if is_lerobot_dataset(path):
            items.append((path, "lerobot"))
            continue
        if not path.exists():
            raise RmbFormatError("no such file or directory", path=path)
        episodes = find_episodes(path)
        datasets = []
        if path.is_dir() and path.suffix != K.COMPACT_SUFFIX:
            datasets = [d for d in sorted(path.iterdir()) if d.is_dir() and is_lerobot_dataset(d)]
        if not episodes and not datasets:
            raise RmbFormatError(
                "no RMB episodes (*.rmb, *.hdf5) or LeRobot datasets (meta/info.json) found",
                path=path,
            )
        items += [(e, e.suffix.lstrip(".").lower()) for e in episodes]
        items += [(d, "lerobot") for d in datasets]
    return items


def verify_paths(
    paths: Sequence[str | Path], *, allow_non_finite: bool = False, progress: bool = True
) -> list[Report]:
    """Verify every episode and dataset in ``paths``.

    Args:
        paths: Episodes, LeRobot dataset roots, or directories holding them.
        allow_non_finite: Do not report NaN/inf in the data.
        progress: Show a tqdm bar of the frames checked (on stderr).

    Returns:
        One report per episode or dataset, in order.

    Raises:
        RmbFormatError: A path holds no episode or dataset.
    """
    items = expand_paths(paths)
    reports = []
    with tqdm(
        total=None, unit="frame", desc="verify", disable=not progress, dynamic_ncols=True
    ) as bar:
        for number, (path, kind) in enumerate(items, 1):
            bar.set_postfix_str(f"{number}/{len(items)} {path.name}")
            report = Report(path, kind)
            started = time.perf_counter()
            check = verify_dataset if kind == "lerobot" else verify_episode
            check(path, report, bar.update, allow_non_finite=allow_non_finite)
            report.seconds = time.perf_counter() - started
            reports.append(report)
    return reports
