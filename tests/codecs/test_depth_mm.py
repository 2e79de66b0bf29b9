"""metres_to_mm on float32 images (float32 arithmetic) equals the float64 formula everywhere."""

from __future__ import annotations

import numpy as np
import pytest

from rmb_lerobot.codecs.depth_base import metres_to_mm


def float64_reference(depth_m: np.ndarray) -> np.ndarray:
    """rint(metres * 1000) in float64; NaN, inf, negative and > 65535 mm -> 0."""
    mm = np.rint(np.asarray(depth_m, dtype=np.float64) * 1000.0)
    valid = np.isfinite(mm) & (mm >= 0) & (mm <= 65535)
    return np.where(valid, mm, 0).astype(np.uint16)


def near_half_millimetres(rng: np.random.Generator, n: int) -> np.ndarray:
    """float32 metres at and one or two float32 steps beside n + 0.5 mm, where float32
    rounding of the product can decide the millimetre."""
    half = (rng.integers(0, 70000, n) + 0.5) / 1000.0
    centre = half.astype(np.float32)
    up = np.nextafter(centre, np.float32(np.inf))
    down = np.nextafter(centre, np.float32(0))
    return np.concatenate([centre, up, down, np.nextafter(up, np.float32(np.inf))])


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_float32_depth_gives_the_float64_millimetres(seed):
    rng = np.random.default_rng(seed)
    values = np.concatenate(
        [
            rng.uniform(0.0, 70.0, 200_000),
            rng.uniform(0.0, 2.0, 200_000),
            rng.uniform(-1.0, 0.001, 1000),
        ]
    ).astype(np.float32)
    values = np.concatenate([values, near_half_millimetres(rng, 50_000)])
    rng.shuffle(values)
    image = values[: values.size // 640 * 640].reshape(-1, 640)
    np.testing.assert_array_equal(metres_to_mm(image), float64_reference(image))


def test_every_exact_half_millimetre_rounds_to_even_like_float64():
    metres = (np.arange(0, 65536 * 2 + 4) / 2000.0).astype(np.float32)
    np.testing.assert_array_equal(metres_to_mm(metres), float64_reference(metres))


def test_values_without_a_millimetre_become_no_data_in_float32_too():
    metres = np.array(
        [np.nan, np.inf, -np.inf, -0.5, -0.0004, -0.0005, 65.5354, 65.5355, 1e30, 3e38],
        dtype=np.float32,
    )
    np.testing.assert_array_equal(metres_to_mm(metres), float64_reference(metres))
    assert metres_to_mm(metres)[6] == 65535 and metres_to_mm(metres)[0] == 0


def test_float16_and_strided_float32_input_match_the_reference():
    rng = np.random.default_rng(7)
    image = rng.uniform(0.0, 3.0, (48, 64)).astype(np.float32)
    flipped = np.flipud(image)  # a view with a negative stride, as the renderer's read-back
    np.testing.assert_array_equal(metres_to_mm(flipped), float64_reference(flipped))
    half = image.astype(np.float16)
    np.testing.assert_array_equal(metres_to_mm(half), float64_reference(half))
    assert metres_to_mm(flipped).dtype == np.uint16 and metres_to_mm(flipped).shape == (48, 64)
