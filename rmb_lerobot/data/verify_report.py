"""What ``rmb-data verify`` found in one episode or dataset, and the summary table.

A :class:`Report` collects findings instead of stopping at the first: each check runs inside
:meth:`Report.check`, which turns the errors of a damaged file into a :class:`Finding`.
"""

from __future__ import annotations

import contextlib
from collections import Counter
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import av

from rmb_lerobot.errors import RmbFormatError

# What reading a damaged file raises besides our own errors (h5py, PyAV, pyarrow, json).
READ_ERRORS = (OSError, RuntimeError, KeyError, ValueError, TypeError, IndexError, av.FFmpegError)


@dataclass(frozen=True)
class Finding:
    """One problem: which check found it and what it is (naming the file, key, frame)."""

    check: str
    message: str


@dataclass
class Report:
    """The result of verifying one RMB episode or LeRobot dataset.

    Attributes:
        path: The episode (``NAME.rmb``, ``NAME.hdf5``) or the dataset's root directory.
        kind: ``rmb`` (compact), ``hdf5`` (single file) or ``lerobot``.
        counts: What was checked: ``datasets`` (HDF5 datasets or parquet files read in
            full), ``frames`` (video frames decoded), ``digests`` (files hashed),
            ``checksummed`` (HDF5 datasets stored with Fletcher-32).
        findings: Every problem found.
    """

    path: Path
    kind: str
    counts: Counter = field(default_factory=Counter)
    findings: list[Finding] = field(default_factory=list)
    seconds: float = 0.0

    @property
    def ok(self) -> bool:
        """Whether nothing was found."""
        return not self.findings

    def to_json(self) -> dict:
        """The report as JSON values (``rmb-data verify --json``).

        Returns:
            ``path``, ``kind``, ``ok``, ``seconds``, ``counts`` and ``findings``.
        """
        return {
            "path": str(self.path),
            "kind": self.kind,
            "ok": self.ok,
            "seconds": round(self.seconds, 3),
            "counts": dict(self.counts),
            "findings": [{"check": f.check, "message": f.message} for f in self.findings],
        }

    def add(self, check: str, message: str) -> None:
        """Record a finding.

        Args:
            check: The check's short name (``hdf5``, ``video``, ``time``, ...).
            message: What is wrong, naming the file (and key, frame).
        """
        self.findings.append(Finding(check, message))

    @contextlib.contextmanager
    def check(self, name: str, where: Path | str | None = None) -> Iterator[None]:
        """Run a check; an error of a damaged file becomes a finding instead of propagating.

        Args:
            name: The check's short name, for the finding.
            where: The file, named in messages that do not name one themselves.

        Yields:
            Nothing; the block is the check.
        """
        try:
            yield
        except RmbFormatError as exc:
            self.add(name, str(exc))
        except READ_ERRORS as exc:
            suffix = f" (file {str(where)!r})" if where is not None else ""
            self.add(name, f"{type(exc).__name__}: {exc}{suffix}")


def _cell(value: int) -> str:
    return str(value) if value else "-"


def format_table(reports: Sequence[Report]) -> str:
    """The summary: one row per episode or dataset, then every finding.

    Args:
        reports: The reports of one run.

    Returns:
        Plain text, ending with a line that counts what was found.
    """
    header = ("path", "kind", "datasets", "checksummed", "frames", "digests", "seconds", "result")
    rows = [
        (
            str(r.path),
            r.kind,
            _cell(r.counts["datasets"]),
            _cell(r.counts["checksummed"]),
            _cell(r.counts["frames"]),
            _cell(r.counts["digests"]),
            f"{r.seconds:.1f}",
            "ok" if r.ok else f"{len(r.findings)} finding{'s' * (len(r.findings) != 1)}",
        )
        for r in reports
    ]
    widths = [max(len(row[i]) for row in (header, *rows)) for i in range(len(header))]
    lines = [
        "  ".join(cell.ljust(w) for cell, w in zip(row, widths, strict=True)).rstrip()
        for row in (header, *rows)
    ]
    for report in reports:
        for finding in report.findings:
            lines.append(f"{report.path}: [{finding.check}] {finding.message}")
    bad = sum(not r.ok for r in reports)
    total = sum(len(r.findings) for r in reports)
    lines.append(
        f"{len(reports)} checked, {bad} with findings ({total} in all)"
        if bad
        else f"{len(reports)} checked, all ok"
    )
    return "\n".join(lines)
