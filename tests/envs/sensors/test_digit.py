"""DIGIT-like tactile images from hand-computed gap maps (pure numpy, no simulator)."""

from __future__ import annotations

import itertools
import math
from dataclasses import replace

import numpy as np
import pytest

from rmb_lerobot.envs.sensors.digit import (
    DigitConfig,
    DigitSensorImage,
    depth_image,
    indentation,
    push_depth,
    reference_image,
    shade,
)

CFG = DigitConfig()  # RMB's 480 x 640
R = 0.01  # sphere radius (m)


def pixel_centres(cfg: DigitConfig) -> tuple[np.ndarray, np.ndarray]:
    """Row (across) and column (along) coordinates of pixel centres, metres from the gel centre."""
    pr, pc = cfg.pitch
    rows = (np.arange(cfg.height) + 0.5) * pr - cfg.gel_across / 2
    cols = (np.arange(cfg.width) + 0.5) * pc - cfg.gel_along / 2
    return rows, cols


def sphere_gap(cfg: DigitConfig, radius: float, centre=(0.0, 0.0), penetration=0.0) -> np.ndarray:
    """Gap map of a sphere whose lowest point is ``penetration`` inside the gel at ``centre``
    (row, column offsets in metres): ``R - sqrt(R^2 - r^2) - penetration``, inf beyond R."""
    rows, cols = pixel_centres(cfg)
    r2 = (rows[:, None] - centre[0]) ** 2 + (cols[None, :] - centre[1]) ** 2
    gap = np.full(r2.shape, np.inf)
    inside = r2 < radius**2
    gap[inside] = radius - np.sqrt(radius**2 - r2[inside]) - penetration
    return gap


def predicted_radius(radius: float, push: float) -> float:
    """Radius of the circle where a sphere pushed ``push`` deep cuts the gel plane."""
    return math.sqrt(2 * radius * push - push**2)


def changed(image: np.ndarray, cfg: DigitConfig) -> np.ndarray:
    """Pixels whose colour differs from the reference."""
    return np.any(image != reference_image(cfg), axis=-1)


def bbox_centre_and_radii(mask: np.ndarray, cfg: DigitConfig):
    """(centre row, centre col) in pixels and (radius across, radius along) in metres."""
    rows = np.flatnonzero(mask.any(axis=1))
    cols = np.flatnonzero(mask.any(axis=0))
    pr, pc = cfg.pitch
    centre = ((rows[0] + rows[-1]) / 2, (cols[0] + cols[-1]) / 2)
    radii = ((rows[-1] - rows[0] + 1) * pr / 2, (cols[-1] - cols[0] + 1) * pc / 2)
    return centre, radii


def area_radius(h: np.ndarray, cfg: DigitConfig) -> float:
    """Radius (m) of the disc of the same area as the indented pixels (pixels are not square)."""
    pr, pc = cfg.pitch
    return math.sqrt(np.count_nonzero(h > 0) * pr * pc / math.pi)


def test_config_defaults_match_rmb_and_tacto():
    assert (CFG.height, CFG.width) == (480, 640)
    assert (CFG.gel_across, CFG.gel_along) == (0.02, 0.03)
    assert CFG.light_azimuths_deg == (30.0, 150.0, 270.0)
    assert CFG.noise_sigma == 7.0 and CFG.zrange == 0.002
    small = DigitConfig.small()
    assert (small.height, small.width) == (60, 80)
    assert small.pitch == pytest.approx((0.02 / 60, 0.03 / 80))
    with pytest.raises(ValueError):
        DigitConfig(height=0)
    with pytest.raises(ValueError):
        DigitConfig(light_azimuths_deg=(0.0,))


def test_push_and_indentation_hand_computed():
    assert push_depth(0.0, CFG) == 0.0
    assert push_depth(50.0, CFG) == pytest.approx(0.0025)
    assert push_depth(100.0, CFG) == pytest.approx(0.005)
    assert push_depth(250.0, CFG) == pytest.approx(0.005)  # clipped at 100 N
    assert push_depth(-3.0, CFG) == 0.0
    gap = np.array([-0.001, 0.0, 0.001, 0.003, np.inf, np.nan])
    np.testing.assert_allclose(
        indentation(gap, 50.0, CFG), [0.0035, 0.0025, 0.0015, 0.0, 0.0, 0.0], atol=1e-7
    )
    np.testing.assert_allclose(
        indentation(gap, 200.0, CFG), [0.006, 0.005, 0.004, 0.002, 0.0, 0.0], atol=1e-7
    )
    # No force: nothing is drawn, even an object that already penetrates (TACTO draws only
    # objects with a contact force).
    assert not indentation(gap, 0.0, CFG).any()


def test_no_contact_is_exactly_the_reference():
    ref = reference_image(CFG)
    assert ref.shape == (480, 640, 3) and ref.dtype == np.uint8
    assert np.all(ref == np.array(CFG.background, dtype=np.uint8))
    nothing = np.full((CFG.height, CFG.width), np.inf)
    sensor = DigitSensorImage(CFG)
    np.testing.assert_array_equal(sensor.render(nothing, 30.0), ref)
    np.testing.assert_array_equal(sensor.render(sphere_gap(CFG, R), 0.0), ref)
    np.testing.assert_array_equal(shade(np.zeros((480, 640)), CFG), ref)


def test_a_flat_press_brightens_evenly_with_depth():
    """A box face filling the gel has no slope: only the contact brightening shows it, evenly,
    by ``contact_gain`` at ``zrange`` and in proportion below."""
    ref = reference_image(CFG).astype(int)
    half = shade(np.full((480, 640), CFG.zrange / 2), CFG).astype(int) - ref
    full = shade(np.full((480, 640), 3 * CFG.zrange), CFG).astype(int) - ref
    assert np.all(np.abs(half - CFG.contact_gain / 2) <= 1)
    assert np.all(full == CFG.contact_gain)
    flat = replace(CFG, contact_gain=0.0)
    np.testing.assert_array_equal(shade(np.full((480, 640), 0.001), flat), ref)


@pytest.mark.parametrize("force", [10.0, 40.0, 100.0])
def test_centred_sphere_gives_disc_of_predicted_radius(force):
    sensor = DigitSensorImage(CFG)
    gap = sphere_gap(CFG, R)
    p = push_depth(force, CFG)
    expected = predicted_radius(R, p)
    h = indentation(gap, force, CFG)
    pr, pc = CFG.pitch
    px = max(pr, pc)
    assert abs(area_radius(h, CFG) - expected) < 1.5 * px
    assert h.max() == pytest.approx(p, abs=1e-6)
    image = sensor.render(gap, force)
    (ci, cj), (ra, rl) = bbox_centre_and_radii(changed(image, CFG), CFG)
    # The shaded disc reaches one pixel past the indented one (central differences).
    assert abs(ra - expected) < 2 * pr and abs(rl - expected) < 2 * pc
    assert abs(ci - (CFG.height - 1) / 2) <= 1 and abs(cj - (CFG.width - 1) / 2) <= 1


def test_off_centre_sphere_gives_off_centre_disc():
    centre = (0.003, -0.006)  # 3 mm across (down), 6 mm along (left)
    force = 20.0  # disc radius 4.5 mm: inside the gel
    pr, pc = CFG.pitch
    image = DigitSensorImage(CFG).render(sphere_gap(CFG, R, centre), force)
    (ci, cj), (ra, rl) = bbox_centre_and_radii(changed(image, CFG), CFG)
    expected_i = (centre[0] + CFG.gel_across / 2) / pr - 0.5
    expected_j = (centre[1] + CFG.gel_along / 2) / pc - 0.5
    assert abs(ci - expected_i) <= 1 and abs(cj - expected_j) <= 1
    expected = predicted_radius(R, push_depth(force, CFG))
    assert abs(ra - expected) < 2 * pr and abs(rl - expected) < 2 * pc


def test_penetrating_sphere_is_pushed_further():
    force = 20.0
    p = push_depth(force, CFG) + 0.0005
    h = indentation(sphere_gap(CFG, R, penetration=0.0005), force, CFG)
    assert abs(area_radius(h, CFG) - predicted_radius(R, p)) < 1.5 * max(CFG.pitch)


def test_more_force_gives_larger_disc_and_clips_at_100n():
    gap = sphere_gap(CFG, R)
    forces = [2.0, 10.0, 25.0, 50.0, 75.0, 100.0]
    radii = [area_radius(indentation(gap, f, CFG), CFG) for f in forces]
    assert all(a < b for a, b in itertools.pairwise(radii)), radii
    sensor = DigitSensorImage(CFG)
    at_clip = sensor.render(gap, 100.0)
    np.testing.assert_array_equal(sensor.render(gap, 150.0), at_clip)
    np.testing.assert_array_equal(sensor.render(gap, 1e4), at_clip)
    assert not np.array_equal(sensor.render(gap, 90.0), at_clip)


def test_noise_has_configured_sigma_and_no_rng_is_deterministic():
    sensor = DigitSensorImage(CFG)
    gap = sphere_gap(CFG, R)
    clean = sensor.render(gap, 30.0)
    np.testing.assert_array_equal(sensor.render(gap, 30.0), clean)
    noisy = sensor.render(gap, 30.0, np.random.default_rng(0)).astype(np.float64)
    diff = noisy - clean
    assert abs(diff.std() - CFG.noise_sigma) < 0.1 * CFG.noise_sigma
    assert abs(diff.mean()) < 0.1
    again = sensor.render(gap, 30.0, np.random.default_rng(0))
    np.testing.assert_array_equal(again, noisy.astype(np.uint8))
    # No contact with noise: fresh noise around the reference.
    untouched = sensor.render(np.full((480, 640), np.inf), 0.0, np.random.default_rng(1))
    d = untouched.astype(np.float64) - reference_image(CFG)
    assert abs(d.std() - CFG.noise_sigma) < 0.1 * CFG.noise_sigma
    sigma3 = DigitConfig.small(noise_sigma=3.0)
    d3 = DigitSensorImage(sigma3).untouched(np.random.default_rng(2)).astype(np.float64)
    assert abs((d3 - reference_image(sigma3)).std() - 3.0) < 0.3


@pytest.mark.parametrize("channel", [0, 1, 2])
def test_slope_towards_a_light_takes_its_colour(channel):
    """Red lights from 30 deg (counter-clockwise from +column, on screen), green from 150, blue
    from 270: the side of the disc towards a light is brighter in its channel than the side
    opposite."""
    force = 60.0
    image = DigitSensorImage(CFG).render(sphere_gap(CFG, R), force).astype(int)
    azimuth = math.radians(CFG.light_azimuths_deg[channel])
    half = predicted_radius(R, push_depth(force, CFG)) / 2
    pr, pc = CFG.pitch
    ci, cj = (CFG.height - 1) / 2, (CFG.width - 1) / 2

    def pixel(sign: float) -> np.ndarray:
        i = round(ci - sign * half * math.sin(azimuth) / pr)  # up on screen is -row
        j = round(cj + sign * half * math.cos(azimuth) / pc)
        return image[i, j]

    towards, away = pixel(+1.0), pixel(-1.0)
    assert towards[channel] > away[channel] + 20, (towards, away)
    assert towards[channel] > CFG.background[channel] > away[channel]


def test_depth_image_uses_zrange():
    h = np.array([[0.0, 0.0005, 0.002, 0.004]])
    np.testing.assert_array_equal(depth_image(h, CFG), [[0, 64, 255, 255]])


def test_shape_mismatch_is_rejected():
    with pytest.raises(ValueError, match="shape"):
        shade(np.zeros((60, 80)), CFG)


def test_small_config_renders_small_images():
    cfg = DigitConfig.small()
    image = DigitSensorImage(cfg).render(sphere_gap(cfg, R), 50.0)
    assert image.shape == (60, 80, 3)
    assert changed(image, cfg).sum() > 20
