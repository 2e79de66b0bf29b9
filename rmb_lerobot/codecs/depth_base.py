"""The depth codec interface: millimetre conversion, writer/reader/codec base classes.

Every depth codec stores uint16 millimetres (0 = "no data"), the unit of the original RMB's
depth videos and of LeRobot's integer depth frames.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from pathlib import Path
from typing import Self

import numpy as np

from rmb_lerobot.codecs.indexing import FrameIndex
from rmb_lerobot.errors import RmbFormatError

MAX_DEPTH_MM = 65535


def metres_to_mm(depth_m: np.ndarray) -> np.ndarray:
    """Depth in metres -> uint16 millimetres, rounded to the nearest mm (ties to even).

    The original RMB truncates (``(depth * 1000).astype(np.uint16)``); rounding halves the
    error to 0.5 mm. Values that have no uint16 millimetre representation are mapped to 0
    ("no data") explicitly, where the original silently wraps them around: NaN, +-inf,
    negative depths, and depths above 65.535 m (after rounding). float32 (and float16) input,
    what renderers and cameras give, is converted in float32 with the same result as the exact
    float64 formula (see :func:`_float32_metres_to_mm`); anything else goes through float64.
    """
    array = np.asarray(depth_m)
    if array.dtype in (np.float32, np.float16):
        return _float32_metres_to_mm(array.astype(np.float32, copy=False))
    return _float64_metres_to_mm(array)


def _float64_metres_to_mm(depth_m: np.ndarray) -> np.ndarray:
    """The reference conversion: exact product in float64, then rint and the range check."""
    mm = np.rint(np.asarray(depth_m, dtype=np.float64) * 1000.0)
    valid = np.isfinite(mm) & (mm >= 0) & (mm <= MAX_DEPTH_MM)
    return np.where(valid, mm, 0).astype(np.uint16)


def _float32_metres_to_mm(depth_m: np.ndarray) -> np.ndarray:
    """float32 metres -> uint16 mm in float32 arithmetic, equal to :func:`_float64_metres_to_mm`.

    A float32 value times 1000 is exact in float64 but rounded in float32. Rounding to nearest
    is monotonic and every half-integer below 2**23 is a float32, so the rounded product can
    only land on the other side of a ``n + 0.5`` boundary by landing exactly on it: those few
    pixels (dozens in a 640x480 image) are redone in float64. Two to three times faster than
    the float64 formula on a rendered step's images (benchmarks/render_depth.py).
    """
    with np.errstate(over="ignore", invalid="ignore"):  # inf, inf - inf: not valid anyway
        product = np.multiply(depth_m, np.float32(1000.0))
        mm = np.rint(product)
        np.subtract(product, mm, out=product)
    ties = np.flatnonzero(np.abs(product, out=product) == np.float32(0.5))
    # 0 <= mm <= 65535 in one comparison (NaN compares False): |mm - 32767.5| <= 32767.5.
    half = np.float32(MAX_DEPTH_MM / 2)
    np.subtract(mm, half, out=product)
    valid = np.abs(product, out=product) <= half
    if not valid.all():
        mm[~valid] = 0
    out = mm.astype(np.uint16)
    if ties.size:
        out.flat[ties] = _float64_metres_to_mm(depth_m.flat[ties])
    return out


def mm_to_metres(depth_mm: np.ndarray) -> np.ndarray:
    """uint16 millimetres -> float32 metres (0 stays 0 = "no data")."""
    return np.asarray(depth_mm).astype(np.float32) / np.float32(1000.0)


def as_depth_mm(frame: np.ndarray, shape: tuple[int, int], path: Path, number: int) -> np.ndarray:
    """Validate one depth frame: uint16 mm or float metres, (H, W) or (H, W, 1) -> uint16 (H, W)."""
    if not isinstance(frame, np.ndarray):
        raise RmbFormatError(
            f"bad depth frame {number}: got {type(frame).__name__}, expected a numpy array of "
            f"uint16 mm or float metres with shape {shape}",
            path=path,
        )
    image = frame[..., 0] if frame.ndim == 3 and frame.shape[2] == 1 else frame
    if image.shape != shape or not (image.dtype == np.uint16 or image.dtype.kind == "f"):
        raise RmbFormatError(
            f"bad depth frame {number}: got {frame.dtype} {frame.shape}, expected uint16 mm or "
            f"float metres with shape {shape}",
            path=path,
        )
    return image if image.dtype == np.uint16 else metres_to_mm(image)


class DepthWriter(ABC):
    """Encodes depth frames as they arrive; ``close()`` finishes the file."""

    path: Path

    @abstractmethod
    def write(self, frame: np.ndarray) -> None:
        """Encode one (H, W) frame: uint16 millimetres or float metres."""

    @abstractmethod
    def close(self) -> None:
        """Flush and finish the file (idempotent)."""

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


class DepthReader(ABC):
    """uint16 millimetre frames by index: ``reader[i]`` (H, W), ``reader[a:b]`` (N, H, W)."""

    path: Path

    @abstractmethod
    def __len__(self) -> int: ...

    @property
    @abstractmethod
    def shape(self) -> tuple[int, int, int]:
        """(N, H, W)."""

    @abstractmethod
    def __getitem__(self, index: FrameIndex) -> np.ndarray: ...

    @abstractmethod
    def close(self) -> None: ...

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


class DepthCodec(ABC):
    """A way to store a depth stream in one file ``<key><file_suffix>``."""

    name: str
    file_suffix: str

    @abstractmethod
    def writer(self, path: str | Path, width: int, height: int) -> DepthWriter: ...

    @abstractmethod
    def reader(self, path: str | Path) -> DepthReader: ...

    def __repr__(self) -> str:
        return f"{type(self).__name__}(name={self.name!r}, file_suffix={self.file_suffix!r})"
