"""One exception type for every problem with RMB data, so callers can catch it in one place."""

from __future__ import annotations

from pathlib import Path


class RmbFormatError(ValueError):
    """Bad or unreadable RMB data: the message names the file (and key) and what was expected.

    Subclasses ``ValueError`` so that code written against the original RMB (which raised
    ``ValueError`` for bad extensions) keeps working.
    """

    def __init__(self, message: str, *, path: str | Path | None = None, key: str | None = None):
        self.path = None if path is None else Path(path)
        self.key = key
        where = []
        if self.path is not None:
            where.append(f"file {str(self.path)!r}")
        if key is not None:
            where.append(f"key {key!r}")
        super().__init__(f"{message} ({', '.join(where)})" if where else message)


class MissingKeyError(RmbFormatError, KeyError):
    """A requested key (or attribute) is not in the episode; also a ``KeyError``."""

    __str__ = BaseException.__str__  # KeyError would quote the whole message
