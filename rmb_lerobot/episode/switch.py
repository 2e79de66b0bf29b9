"""Convert an episode between the compact and single-file variants (RMB's SwitchRmbDataFormat)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rmb_lerobot import keys as K
from rmb_lerobot.episode.reader import open_episode
from rmb_lerobot.episode.writer import EpisodeWriter

# Frames decoded per read while copying video; bounds memory for long episodes.
_CHUNK = 32


def switch_format(
    src: str | Path,
    dst: str | Path,
    *,
    overwrite: bool = False,
    depth_codec: str = "rmb-videoio",
) -> Path:
    """Write ``src`` again as ``dst`` in the variant ``dst``'s extension names.

    Every key and attribute is kept as stored (no relative keys or poses are recomputed); the
    images are re-encoded, so RGB going into the compact variant is lossy (H.264) and depth is
    rounded to millimetres, exactly as in the original tool.
    """
    with open_episode(src) as episode:
        episode.validate()
        attrs = {k: v for k, v in episode.attrs.items() if k != K.ATTR_FORMAT}
        lowdim = {k: np.asarray(episode[k][:]) for k in episode if not K.is_image_key(k)}
        images = {k: episode[k] for k in episode if K.is_image_key(k)}
        with EpisodeWriter(
            dst, attrs, derive_relative=False, depth_codec=depth_codec, overwrite=overwrite
        ) as writer:
            for start in range(0, len(episode), _CHUNK):
                stop = min(start + _CHUNK, len(episode))
                frames = {k: series[start:stop] for k, series in images.items()}
                for i in range(start, stop):
                    step = {k: v[i] for k, v in lowdim.items()}
                    step.update({k: v[i - start] for k, v in frames.items()})
                    writer.append(step)
    return Path(dst)
