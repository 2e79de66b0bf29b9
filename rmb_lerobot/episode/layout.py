"""Where each piece of an RMB episode lives on disk, for both variants."""

from __future__ import annotations

from enum import Enum
from pathlib import Path

from rmb_lerobot import keys as K
from rmb_lerobot.errors import RmbFormatError

RGB_VIDEO_SUFFIX = ".rmb.mp4"


class EpisodeFormat(Enum):
    """The two RMB variants; the value is what the ``format`` attribute holds."""

    COMPACT = K.FORMAT_COMPACT  # NAME.rmb/ = main.rmb.hdf5 + one MP4 per image key
    SINGLE_HDF5 = K.FORMAT_SINGLE_HDF5  # NAME.hdf5 with images as datasets

    @property
    def short_name(self) -> str:
        """The CLI/writer name: ``rmb`` or ``hdf5``."""
        return "rmb" if self is EpisodeFormat.COMPACT else "hdf5"

    @classmethod
    def from_name(cls, name: str) -> EpisodeFormat:
        for fmt in cls:
            if name in (fmt.short_name, fmt.value):
                return fmt
        raise ValueError(f"unknown episode format {name!r}; expected 'rmb' or 'hdf5'")

    def hdf5_path(self, episode_path: Path) -> Path:
        return episode_path / K.COMPACT_MAIN_FILE if self is EpisodeFormat.COMPACT else episode_path

    def describe(self) -> str:
        if self is EpisodeFormat.COMPACT:
            return f"a directory NAME{K.COMPACT_SUFFIX}/ holding {K.COMPACT_MAIN_FILE}"
        return f"a file NAME{K.SINGLE_HDF5_SUFFIX}"


def episode_format(path: str | Path) -> EpisodeFormat:
    """The variant of an episode path, chosen by its extension (as the original RMB does)."""
    path = Path(path)
    name = path.name
    if name.endswith(K.COMPACT_MAIN_FILE.removeprefix("main")):
        raise RmbFormatError(
            f"this is the inner file of a compact episode; open its {K.COMPACT_SUFFIX} directory",
            path=path,
        )
    if path.suffix.lower() == K.COMPACT_SUFFIX:
        return EpisodeFormat.COMPACT
    if path.suffix.lower() == K.SINGLE_HDF5_SUFFIX:
        return EpisodeFormat.SINGLE_HDF5
    raise RmbFormatError(
        f"invalid episode extension {path.suffix!r}: expected '{K.COMPACT_SUFFIX}' (a directory) "
        f"or '{K.SINGLE_HDF5_SUFFIX}' (a file)",
        path=path,
    )


def rgb_video_path(episode_dir: Path, key: str) -> Path:
    """``front_rgb_image`` -> ``NAME.rmb/front_rgb_image.rmb.mp4``."""
    return episode_dir / f"{key}{RGB_VIDEO_SUFFIX}"
