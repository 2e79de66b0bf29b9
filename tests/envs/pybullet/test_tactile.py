"""DIGIT-like tactile images in PyBullet: force, disc position and size, mirrored pads."""

from __future__ import annotations

import math

import numpy as np
import pybullet as p
import pytest

from rmb_lerobot.envs.pybullet.tactile import (
    PadSpec,
    RayOptions,
    TactilePads,
    pad_forces,
    render_pad,
    upsample,
)
from rmb_lerobot.envs.sensors.digit import DigitConfig, push_depth, reference_image

CFG = DigitConfig()  # 480 x 640, gel 0.02 m across (rows) x 0.03 m along (columns)
R = 0.01  # sphere radius (m)
PAD_HALF = (0.015, 0.01, 0.005)  # pad box half extents: along (x), across (y), thickness (z)
G = 9.81


@pytest.fixture
def client():
    cid = p.connect(p.DIRECT)
    yield cid
    p.disconnect(cid)


def _sphere(cid: int, mass: float, pos) -> int:
    shape = p.createCollisionShape(p.GEOM_SPHERE, radius=R, physicsClientId=cid)
    return p.createMultiBody(mass, shape, basePosition=pos, physicsClientId=cid)


def _pad_on_link(cid: int) -> int:
    """A fixed base with one fixed link carrying the pad box; its top face (z = +0.005 in the
    link frame) is the gel."""
    box = p.createCollisionShape(p.GEOM_BOX, halfExtents=PAD_HALF, physicsClientId=cid)
    return p.createMultiBody(
        0,
        -1,
        basePosition=[0, 0, 0],
        linkMasses=[0.1],
        linkCollisionShapeIndices=[box],
        linkVisualShapeIndices=[-1],
        linkPositions=[[0, 0, 0]],
        linkOrientations=[[0, 0, 0, 1]],
        linkInertialFramePositions=[[0, 0, 0]],
        linkInertialFrameOrientations=[[0, 0, 0, 1]],
        linkParentIndices=[0],
        linkJointTypes=[p.JOINT_FIXED],
        linkJointAxis=[[0, 0, 1]],
        physicsClientId=cid,
    )


# Gel on the link's +z face; columns along link x, rows along link y (= z x x).
UP_PAD = PadSpec(link=0, center=(0.0, 0.0, PAD_HALF[2]), normal=(0, 0, 1), along=(1, 0, 0))


def _settle(cid: int, steps: int = 240) -> None:
    for _ in range(steps):
        p.stepSimulation(physicsClientId=cid)


def _disc(h: np.ndarray) -> tuple[tuple[float, float], float]:
    """Centre (row, col) in pixels of the bounding box of ``h > 0`` and the radius (m) of the
    disc of equal area (pixels are 41.7 x 46.9 um)."""
    mask = h > 0
    rows = np.flatnonzero(mask.any(axis=1))
    cols = np.flatnonzero(mask.any(axis=0))
    pr, pc = CFG.pitch
    radius = math.sqrt(mask.sum() * pr * pc / math.pi)
    return ((rows[0] + rows[-1]) / 2, (cols[0] + cols[-1]) / 2), radius


def _pixel(across: float, along: float) -> tuple[float, float]:
    """Pixel (row, col) of a point on the gel given in metres from its centre."""
    pr, pc = CFG.pitch
    return (across + CFG.gel_across / 2) / pr - 0.5, (along + CFG.gel_along / 2) / pc - 0.5


def _sphere_radius(push: float) -> float:
    return math.sqrt(2 * R * push - push**2)


def test_pad_spec_axes():
    pad = PadSpec(link=3, center=(0, 0, 0), normal=(0, 0, 2), along=(1, 0, 0))
    assert pad.across == (0.0, 1.0, 0.0) and pad.normal == (0.0, 0.0, 1.0)
    PadSpec(link=3, center=(0, 0, 0), normal=(0, 0, 1), along=(1, 0, 0), across=(0, 1, 0))
    with pytest.raises(ValueError, match="right-handed"):
        PadSpec(link=3, center=(0, 0, 0), normal=(0, 0, 1), along=(1, 0, 0), across=(0, -1, 0))
    with pytest.raises(ValueError, match="perpendicular"):
        PadSpec(link=3, center=(0, 0, 0), normal=(0, 0, 1), along=(1, 0, 1))
    pts = UP_PAD.grid_points((2, 4))
    assert pts.shape == (8, 3)
    np.testing.assert_allclose(pts[0], [-0.01125, -0.005, 0.005])  # row 0 at -across
    np.testing.assert_allclose(pts[-1], [0.01125, 0.005, 0.005])


def test_upsample_reproduces_quadratics():
    n, m = (24, 32), (480, 640)
    yc = (np.arange(n[0]) + 0.5) / n[0]
    xc = (np.arange(n[1]) + 0.5) / n[1]
    yf = (np.arange(m[0]) + 0.5) / m[0]
    xf = (np.arange(m[1]) + 0.5) / m[1]

    def f(y, x):
        return 0.3 * (y[:, None] - 0.4) ** 2 - 0.2 * (x[None, :] - 0.6) ** 2 + 0.1 * y[:, None]

    fine = upsample(f(yc, xc), m)
    inner = (slice(40, -40), slice(40, -40))  # 2 cells from the replicated borders
    np.testing.assert_allclose(fine[inner], f(yf, xf)[inner], atol=1e-6)
    # A part is the same part of the whole; a constant stays constant (pixels far from any
    # touching cell stay at the floor, which is why only the part near contact is resampled).
    part = upsample(f(yc, xc), m, slice(100, 230), slice(7, 600))
    np.testing.assert_allclose(part, fine[100:230, 7:600], atol=1e-7)
    np.testing.assert_allclose(upsample(np.full(n, -0.001), m), -0.001, atol=1e-9)


def test_sphere_under_gravity_gives_predicted_force_and_disc(client):
    pad = _pad_on_link(client)
    p.setGravity(0, 0, -G, physicsClientId=client)
    mass, offset = 2.0, (-0.002, 0.003)  # across (y), along (x) from the gel centre
    sphere = _sphere(client, mass, [offset[1], offset[0], PAD_HALF[2] + R])
    _settle(client)
    contacts = p.getContactPoints(bodyA=pad, linkIndexA=0, physicsClientId=client)
    penetration = max(0.0, -min(c[8] for c in contacts))
    assert penetration < 1e-4

    force = pad_forces(client, pad, 0, {sphere})[sphere]
    assert force == pytest.approx(mass * G, rel=0.1)

    (reading,) = TactilePads(client, pad, [UP_PAD], [sphere]).read()
    assert reading.force == pytest.approx(force)
    assert reading.image.shape == (480, 640, 3) and reading.image.dtype == np.uint8
    (ci, cj), radius = _disc(reading.indentation)
    ei, ej = _pixel(*offset)
    assert abs(ci - ei) <= 2 and abs(cj - ej) <= 2
    push = push_depth(force, CFG) + penetration
    assert radius == pytest.approx(_sphere_radius(push), abs=2 * max(CFG.pitch))
    assert reading.indentation.max() == pytest.approx(push, abs=2e-5)
    # The shaded disc sits where the indentation is (one pixel wider: central differences).
    changed = np.any(reading.image != reference_image(CFG), axis=-1)
    (si, sj), _ = _disc(changed)
    assert abs(si - ei) <= 2 and abs(sj - ej) <= 2
    # The one-shot helper gives the same image.
    np.testing.assert_array_equal(render_pad(client, pad, UP_PAD, [sphere]), reading.image)


def test_heavier_sphere_gives_larger_disc(client):
    pad = _pad_on_link(client)
    p.setGravity(0, 0, -G, physicsClientId=client)
    sphere = _sphere(client, 0.5, [0, 0, PAD_HALF[2] + R])
    pads = TactilePads(client, pad, [UP_PAD], [sphere], DigitConfig.small())
    radii = []
    for mass in (0.5, 2.0, 6.0):
        p.changeDynamics(sphere, -1, mass=mass, physicsClientId=client)
        _settle(client, 120)
        (reading,) = pads.read()
        assert reading.force == pytest.approx(mass * G, rel=0.1)
        assert reading.image.shape == (60, 80, 3)
        radii.append(np.count_nonzero(reading.indentation))
    assert radii[0] < radii[1] < radii[2], radii


def test_no_contact_gives_reference(client):
    pad = _pad_on_link(client)
    p.setGravity(0, 0, -G, physicsClientId=client)
    floating = _sphere(client, 0.0, [0, 0, PAD_HALF[2] + R + 0.001])  # 1 mm above the gel
    resting = _sphere(client, 1.0, [0.05, 0, PAD_HALF[2] + R])  # off the pad, no contact
    _settle(client, 60)
    ref = reference_image(CFG)
    (reading,) = TactilePads(client, pad, [UP_PAD], [floating, resting]).read()
    assert reading.force == 0.0 and reading.gap is None
    np.testing.assert_array_equal(reading.image, ref)
    assert not reading.indentation.any()
    # Noise only, around the reference.
    noisy = render_pad(client, pad, UP_PAD, [floating], rng=np.random.default_rng(0))
    assert abs((noisy.astype(float) - ref).std() - CFG.noise_sigma) < 0.1 * CFG.noise_sigma


def test_bodies_not_registered_are_invisible(client):
    pad = _pad_on_link(client)
    p.setGravity(0, 0, -G, physicsClientId=client)
    sphere = _sphere(client, 2.0, [0, 0, PAD_HALF[2] + R])
    _settle(client)
    assert pad_forces(client, pad, 0, set()) == {}
    np.testing.assert_array_equal(render_pad(client, pad, UP_PAD, []), reference_image(CFG))
    # The robot itself never counts, even when listed.
    assert render_pad(client, pad, UP_PAD, [pad, sphere]).shape == (480, 640, 3)


def test_pad_on_base_link_uses_the_urdf_frame(client):
    """Link -1: the pad spec is in the base's URDF frame, not its (offset) inertial frame."""
    box = p.createCollisionShape(p.GEOM_BOX, halfExtents=PAD_HALF, physicsClientId=client)
    base = p.createMultiBody(
        0,
        box,
        basePosition=[0.0, 0.0, 0.0],
        baseInertialFramePosition=[0.004, 0.002, 0.0],
        physicsClientId=client,
    )
    p.setGravity(0, 0, -G, physicsClientId=client)
    top = p.getAABB(base, -1, physicsClientId=client)[1][2]
    sphere = _sphere(client, 1.0, [0.004, 0.002, top + R])
    _settle(client)
    # The URDF frame is the box centre: the box's AABB centre.
    lo, hi = p.getAABB(base, -1, physicsClientId=client)
    centre = (np.asarray(lo) + np.asarray(hi)) / 2
    spec = PadSpec(link=-1, center=(0, 0, PAD_HALF[2]), normal=(0, 0, 1), along=(1, 0, 0))
    (reading,) = TactilePads(client, base, [spec], [sphere]).read()
    pos = p.getBasePositionAndOrientation(sphere, physicsClientId=client)[0]
    (ci, cj), _ = _disc(reading.indentation)
    ei, ej = _pixel(pos[1] - centre[1], pos[0] - centre[0])
    assert abs(ci - ei) <= 2 and abs(cj - ej) <= 2


def _gripper(cid: int, force: float, sphere_yz: tuple[float, float]) -> tuple[int, int]:
    """Two prismatic fingers squeezing a free sphere with ``force`` each, no gravity.

    The right finger's frame is the left one turned by pi about z (as RMB's WSG50), so in both
    link frames +x points at the sphere and the same :class:`PadSpec` fits both.
    """
    half = (0.002, 0.01, 0.015)  # thickness (x), across (y), along (z)
    box = p.createCollisionShape(p.GEOM_BOX, halfExtents=half, physicsClientId=cid)
    x0 = R + half[0] + 0.0005
    gripper = p.createMultiBody(
        0,
        -1,
        basePosition=[0, 0, 0],
        linkMasses=[0.1, 0.1],
        linkCollisionShapeIndices=[box, box],
        linkVisualShapeIndices=[-1, -1],
        linkPositions=[[-x0, 0, 0], [x0, 0, 0]],
        linkOrientations=[[0, 0, 0, 1], p.getQuaternionFromEuler([0, 0, math.pi])],
        linkInertialFramePositions=[[0, 0, 0]] * 2,
        linkInertialFrameOrientations=[[0, 0, 0, 1]] * 2,
        linkParentIndices=[0, 0],
        linkJointTypes=[p.JOINT_PRISMATIC] * 2,
        linkJointAxis=[[1, 0, 0]] * 2,
        physicsClientId=cid,
    )
    sphere = _sphere(cid, 0.05, [0, *sphere_yz])
    p.setGravity(0, 0, 0, physicsClientId=cid)
    p.setJointMotorControlArray(
        gripper, [0, 1], p.VELOCITY_CONTROL, forces=[0, 0], physicsClientId=cid
    )
    for j in (0, 1):
        p.changeDynamics(gripper, j, jointDamping=2.0, physicsClientId=cid)
    for _ in range(480):
        p.setJointMotorControlArray(
            gripper, [0, 1], p.TORQUE_CONTROL, forces=[force, force], physicsClientId=cid
        )
        p.stepSimulation(physicsClientId=cid)
    return gripper, sphere


FINGER_PAD = {"center": (0.002, 0.0, 0.0), "normal": (1, 0, 0), "along": (0, 0, 1)}


def test_mirrored_pads_give_mirror_images(client):
    force, y, z = 10.0, 0.003, 0.004
    gripper, sphere = _gripper(client, force, (y, z))
    pads = [PadSpec(link=j, **FINGER_PAD) for j in (0, 1)]
    left, right = TactilePads(client, gripper, pads, [sphere]).read()
    assert left.force == pytest.approx(force, rel=0.1)
    assert right.force == pytest.approx(force, rel=0.1)
    # Left across = x × z = -y (world), right across = +y: the sphere's +y shows up above the
    # centre on the left, below it on the right; along (+z) is the same for both.
    (li, lj), lr = _disc(left.indentation)
    (ri, rj), rr = _disc(right.indentation)
    ei, ej = _pixel(-y, z)
    assert abs(li - ei) <= 2 and abs(lj - ej) <= 2
    assert abs(ri - (CFG.height - 1 - ei)) <= 2 and abs(rj - ej) <= 2
    expected = _sphere_radius(push_depth(force, CFG))
    assert lr == pytest.approx(expected, abs=2 * max(CFG.pitch))
    assert rr == pytest.approx(expected, abs=2 * max(CFG.pitch))
    # Geometry is an exact mirror image (rows flipped).
    flipped = right.indentation[::-1]
    assert np.abs(left.indentation - flipped).max() < 0.05 * left.indentation.max()
    ref = reference_image(CFG)
    lmask = np.any(left.image != ref, axis=-1)
    rmask = np.any(right.image != ref, axis=-1)[::-1]
    assert (lmask & rmask).sum() / (lmask | rmask).sum() > 0.95


def test_centred_squeeze_gives_matching_images(client):
    """A sphere centred between the pads: its disc is symmetric, so the mirror image is the
    image itself, and both sensors (same lights) give the same colours."""
    gripper, sphere = _gripper(client, 10.0, (0.0, 0.0))
    pads = [PadSpec(link=j, **FINGER_PAD) for j in (0, 1)]
    left, right = TactilePads(client, gripper, pads, [sphere], rays=RayOptions()).render()
    diff = np.abs(left.astype(int) - right.astype(int))
    # The sphere sits 4 um off the middle, so a few rim pixels (0.2 %) flip in or out of the disc.
    assert diff.mean() < 0.5 and np.percentile(diff, 99) <= 2
    assert np.any(left != reference_image(CFG))
