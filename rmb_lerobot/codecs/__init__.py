"""Video and depth codecs for RMB episodes.

- :mod:`rmb_lerobot.codecs.video`: random-access decoding of MP4/MKV files and the RGB streams
  of ``.rmb`` episodes (:class:`RgbVideoWriter`, :class:`RgbVideoReader`).
- :mod:`rmb_lerobot.codecs.depth`: depth codecs by name (``rmb-videoio``, the original's;
  ``rmbz``, ours), :func:`get_depth_codec`, :func:`find_depth_file`, mm/metre conversion.
"""

from rmb_lerobot.codecs.depth import (
    DEPTH_CODECS,
    DepthCodec,
    DepthReader,
    DepthWriter,
    find_depth_file,
    get_depth_codec,
    metres_to_mm,
    mm_to_metres,
)
from rmb_lerobot.codecs.video import RgbVideoReader, RgbVideoWriter, VideoFrameReader

__all__ = [
    "DEPTH_CODECS",
    "DepthCodec",
    "DepthReader",
    "DepthWriter",
    "RgbVideoReader",
    "RgbVideoWriter",
    "VideoFrameReader",
    "find_depth_file",
    "get_depth_codec",
    "metres_to_mm",
    "mm_to_metres",
]
