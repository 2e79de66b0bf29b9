"""Depth codecs by name, and finding a depth stream's file in an ``.rmb`` episode directory.

Codecs:

- ``rmb-videoio``: the original RMB depth video, lossless (``<camera>_depth_image.rmb.mp4``).
- ``rmbz``: ours, max error 1 mm, smaller and with cheap random access
  (``<camera>_depth_image.rmbz``); ``rmbz-exact`` is the same codec without quantisation.

Typical use::

    codec = get_depth_codec("rmbz")
    with codec.writer(episode_dir / f"front_depth_image{codec.file_suffix}", 640, 480) as w:
        for depth_m in frames:  # float metres or uint16 mm
            w.write(depth_m)
    path, codec = find_depth_file(episode_dir, "front_depth_image")
    with codec.reader(path) as r:
        depth_mm = r[10]  # uint16 (480, 640)
"""

from __future__ import annotations

from pathlib import Path

from rmb_lerobot.codecs.depth_base import (
    DepthCodec,
    DepthReader,
    DepthWriter,
    metres_to_mm,
    mm_to_metres,
)
from rmb_lerobot.codecs.rmbz import RmbzCodec
from rmb_lerobot.codecs.videoio_depth import VideoioDepthCodec

__all__ = [
    "DEPTH_CODECS",
    "DepthCodec",
    "DepthReader",
    "DepthWriter",
    "find_depth_file",
    "get_depth_codec",
    "metres_to_mm",
    "mm_to_metres",
]

DEPTH_CODECS: dict[str, DepthCodec] = {
    codec.name: codec
    for codec in (
        VideoioDepthCodec("rmb-videoio"),
        RmbzCodec("rmbz", step_mm=3),
        RmbzCodec("rmbz-exact", step_mm=1),
    )
}


def get_depth_codec(name: str) -> DepthCodec:
    """The registered codec called ``name``; ValueError lists the known names otherwise."""
    try:
        return DEPTH_CODECS[name]
    except KeyError:
        raise ValueError(
            f"unknown depth codec {name!r}; known codecs: {', '.join(sorted(DEPTH_CODECS))}"
        ) from None


def find_depth_file(directory: str | Path, key: str) -> tuple[Path, DepthCodec] | None:
    """``(path, codec)`` of ``<directory>/<key><file_suffix>`` for a registered codec, or None.

    Codecs sharing a suffix read each other's files (their files describe themselves), so the
    first registered one is returned.
    """
    directory = Path(directory)
    for codec in DEPTH_CODECS.values():
        path = directory / f"{key}{codec.file_suffix}"
        if path.is_file():
            return path, codec
    return None
