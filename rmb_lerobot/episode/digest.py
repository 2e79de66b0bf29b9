"""SHA-256 digests of an episode's video files, recorded in its ``video_sha256`` attribute.

HDF5 checks its own datasets (the writer stores them with the Fletcher-32 filter, which every
HDF5 reader verifies on every read), but MP4 files carry no checksum: a flipped byte in their
slice data decodes to a wrong frame without any error. So the writer records, when an episode
is finished, one line per video file in the root attribute ``video_sha256``, in the format of
``sha256sum`` (``<64 hex digits>  <file name>``), so that the text saved to a file in the
episode directory can also be checked with ``sha256sum -c``. The original RMB ignores
attributes it does not know, and episodes it wrote have no such attribute: their videos
cannot be checked.
"""

from __future__ import annotations

import hashlib
import re
from collections.abc import Iterable, Mapping
from pathlib import Path

from rmb_lerobot.errors import MissingKeyError, RmbFormatError

ATTR_VIDEO_SHA256 = "video_sha256"
"""Root attribute of a compact episode: ``sha256sum``-style lines, one per video file."""

_LINE = re.compile(r"(?P<digest>[0-9a-f]{64}) [ *](?P<name>[^/\\]+)")
_BLOCK = 1 << 20


def file_sha256(path: str | Path) -> str:
    """The SHA-256 of a file's bytes, as 64 lowercase hex digits.

    Args:
        path: The file to hash.

    Returns:
        The hex digest.
    """
    digest = hashlib.sha256()
    with open(path, "rb") as file:
        while block := file.read(_BLOCK):
            digest.update(block)
    return digest.hexdigest()


def format_digests(files: Iterable[Path]) -> str:
    """The ``video_sha256`` attribute for ``files`` (sorted by name, one line each).

    Args:
        files: The finished video files of one episode directory.

    Returns:
        ``sha256sum``-style text: ``<hex>  <name>`` lines, each ending in a newline.
    """
    lines = [f"{file_sha256(f)}  {f.name}\n" for f in sorted(files, key=lambda f: f.name)]
    return "".join(lines)


def parse_digests(text: object, h5_path: Path) -> dict[str, str]:
    """File name -> hex digest from a ``video_sha256`` attribute.

    Args:
        text: The attribute as the reader decoded it (a ``str``).
        h5_path: The HDF5 file holding it, for error messages.

    Returns:
        The recorded digests by file name.

    Raises:
        RmbFormatError: The attribute is not ``sha256sum``-style text.
    """
    if not isinstance(text, str):
        raise RmbFormatError(
            f"attribute holds {type(text).__name__}; expected sha256sum-style text",
            path=h5_path,
            key=ATTR_VIDEO_SHA256,
        )
    digests = {}
    for number, line in enumerate(text.splitlines(), 1):
        match = _LINE.fullmatch(line)
        if match is None:
            raise RmbFormatError(
                f"line {number} is {line[:100]!r}; expected '<64 hex digits>  <file name>'",
                path=h5_path,
                key=ATTR_VIDEO_SHA256,
            )
        digests[match["name"]] = match["digest"]
    return digests


def check_digests(directory: Path, digests: Mapping[str, str]) -> None:
    """Hash every recorded file of ``directory`` and compare with its recorded digest.

    Args:
        directory: The episode directory (``NAME.rmb``).
        digests: File name -> recorded hex digest (:func:`parse_digests`).

    Raises:
        MissingKeyError: A recorded file is missing.
        RmbFormatError: A file's bytes differ from those recorded when it was written.
    """
    for name, expected in digests.items():
        path = directory / name
        if not path.is_file():
            raise MissingKeyError(
                f"video file recorded in the {ATTR_VIDEO_SHA256!r} attribute is missing",
                path=path,
            )
        actual = file_sha256(path)
        if actual != expected:
            raise RmbFormatError(
                f"sha256 {actual[:16]}... differs from the {expected[:16]}... recorded when the "
                f"episode was written (attribute {ATTR_VIDEO_SHA256!r}): the file was changed or "
                "is corrupt",
                path=path,
            )
