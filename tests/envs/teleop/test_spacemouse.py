"""The SpaceMouse device against a fake ``pyspacemouse`` 2.x module (scripted HID states).

Scripts are what the hardware reports (HID axes); the fake hands them out in the convention
the device asks for, as pyspacemouse does, so these tests check that the device's result is
RMB's formula applied to the legacy (1.x) axes RMB was written against.
"""

from __future__ import annotations

import sys

import numpy as np
import pytest

from rmb_lerobot.envs.teleop.device import CartesianDelta
from rmb_lerobot.envs.teleop.fakes.spacemouse import (
    AXES,
    AxisConvention,
    FakePySpaceMouse,
    FakeState,
    convert,
)
from rmb_lerobot.envs.teleop.spacemouse import SpaceMouseConfig, SpaceMouseDevice


def install(monkeypatch, scripts, **kwargs) -> FakePySpaceMouse:
    fake = FakePySpaceMouse(scripts, **kwargs)
    monkeypatch.setitem(sys.modules, "pyspacemouse", fake)
    return fake


def rmb_formula(legacy: FakeState) -> tuple[np.ndarray, np.ndarray, float]:
    """RMB's SpacemouseInputDevice.set_command_data, written out."""
    dpos = 1e-2 * np.array([-1.0 * legacy.y, legacy.x, legacy.z])
    drpy = 5e-3 * np.array([-1.0 * legacy.roll, -1.0 * legacy.pitch, -2.0 * legacy.yaw])
    b = legacy.buttons
    dgripper = 5.0 if b[0] > 0 and b[-1] <= 0 else -5.0 if b[-1] > 0 and b[0] <= 0 else 0.0
    return dpos, drpy, dgripper


def random_states(seed: int, n: int) -> list[FakeState]:
    rng = np.random.default_rng(seed)
    states = []
    for i in range(n):
        axes = dict(zip(AXES, rng.uniform(-1, 1, 6), strict=True))
        buttons = [int(b) for b in rng.integers(0, 2, 2)]
        states.append(FakeState(t=float(i), buttons=buttons, **axes))
    return states


def test_axes_map_as_rmbs_on_the_legacy_axes(monkeypatch):
    for seed in range(4):
        states = random_states(seed, 10)
        fake = install(monkeypatch, {"/dev/hidraw0": states})
        # reads_per_step=1: one scripted state per step, to compare them one by one.
        with SpaceMouseDevice(SpaceMouseConfig(reads_per_step=1)) as mouse:
            for state in states:
                delta = mouse.read().arms[0]
                dpos, drpy, dgripper = rmb_formula(convert(state, AxisConvention.LEGACY))
                np.testing.assert_allclose(delta.dpos, dpos, atol=1e-15)
                np.testing.assert_allclose(delta.drpy, drpy, atol=1e-15)
                assert delta.dgripper == dgripper
        # Opened in the raw HID convention (not the deprecated LEGACY), and closed after.
        assert fake.opened[0].convention == AxisConvention.HID and fake.opened[0].closed


def test_physical_motions_move_the_target_as_in_rmb(monkeypatch):
    # Full deflection: the cap pushed right (HID +x) moves the target +y by 1 cm; pulled up
    # (HID -z) moves it +z; twisted counter-clockwise seen from above (HID -yaw) yaws it by
    # +2 x 5 mrad... each exactly as RMB's formula on pyspacemouse 1.x axes.
    cases = {
        "x": (1.0, [0, 0.01, 0], [0, 0, 0]),
        "y": (-1.0, [-0.01, 0, 0], [0, 0, 0]),
        "z": (-1.0, [0, 0, 0.01], [0, 0, 0]),
        "yaw": (-1.0, [0, 0, 0], [0, 0, 0.01]),
        "roll": (1.0, [0, 0, 0], [0, 0.005, 0]),
        "pitch": (1.0, [0, 0, 0], [0.005, 0, 0]),
    }
    for axis, (value, dpos, drpy) in cases.items():
        install(monkeypatch, {"/dev/hidraw0": [FakeState(**{axis: value})]})
        with SpaceMouseDevice() as mouse:
            delta = mouse.read().arms[0]
        np.testing.assert_allclose(delta.dpos, dpos, atol=1e-15, err_msg=axis)
        np.testing.assert_allclose(delta.drpy, drpy, atol=1e-15, err_msg=axis)


@pytest.mark.parametrize(
    ("buttons", "dgripper"),
    [([1, 0], 5.0), ([0, 1], -5.0), ([1, 1], 0.0), ([0, 0], 0.0), ([0, 0, 1], -5.0), ([], 0.0)],
)
def test_first_button_alone_closes_last_alone_opens(monkeypatch, buttons, dgripper):
    install(monkeypatch, {"/dev/hidraw0": [FakeState(buttons=buttons)]})
    with SpaceMouseDevice() as mouse:
        assert mouse.read().arms[0].dgripper == dgripper


def test_each_step_reads_ten_times_and_uses_the_newest_state(monkeypatch):
    queued = [FakeState(x=0.1 * i) for i in range(1, 21)]  # stale reports, newest last
    fake = install(monkeypatch, {"/dev/hidraw0": queued})
    with SpaceMouseDevice() as mouse:
        first = mouse.read().arms[0]
        second = mouse.read().arms[0]
    assert fake.opened[0].reads == 20
    assert first.dpos[1] == pytest.approx(1e-2 * 1.0) and second.dpos[1] == pytest.approx(0.02)


def test_one_device_per_arm_opened_by_path(monkeypatch):
    fake = install(
        monkeypatch,
        {"/dev/hidraw3": [FakeState(x=1.0)], "/dev/hidraw5": [FakeState(z=-1.0, buttons=[1, 0])]},
    )
    config = SpaceMouseConfig(paths=("/dev/hidraw5", "/dev/hidraw3"))
    with SpaceMouseDevice(config) as mouse:
        reading = mouse.read()
    assert [d.path for d in fake.opened] == ["/dev/hidraw5", "/dev/hidraw3"]
    assert isinstance(reading.arms[0], CartesianDelta) and set(reading.arms) == {0, 1}
    np.testing.assert_allclose(reading.arms[0].dpos, [0, 0, 0.01])  # arm 0: hidraw5
    assert reading.arms[0].dgripper == 5.0 and reading.arms[1].dgripper == 0.0
    np.testing.assert_allclose(reading.arms[1].dpos, [0, 0.01, 0])  # arm 1: hidraw3
    assert all(d.closed for d in fake.opened)


def test_errors_name_the_path_the_extra_and_the_system_hidapi(monkeypatch):
    install(monkeypatch, {"/dev/hidraw0": []})
    with pytest.raises(ConnectionError, match="/dev/hidraw7"):
        SpaceMouseDevice(SpaceMouseConfig(paths=("/dev/hidraw7",))).connect()
    install(monkeypatch, {"/dev/hidraw0": []}, hidapi_missing=True)
    with pytest.raises(ConnectionError, match="libhidapi-hidraw0"):
        SpaceMouseDevice().connect()
    monkeypatch.setitem(sys.modules, "pyspacemouse", None)
    with pytest.raises(ImportError, match=r"lerobot_env_rmb\[spacemouse\].*hidapi"):
        SpaceMouseDevice().connect()
    with pytest.raises(RuntimeError, match="not connected"):
        SpaceMouseDevice().read()
    with pytest.raises(ValueError, match="distinct"):
        SpaceMouseConfig(paths=("/dev/hidraw0", "/dev/hidraw0"))


def test_a_failed_second_device_closes_the_first(monkeypatch):
    fake = install(monkeypatch, {"/dev/hidraw0": [FakeState()]})
    mouse = SpaceMouseDevice(SpaceMouseConfig(paths=("/dev/hidraw0", "/dev/hidraw1")))
    with pytest.raises(ConnectionError, match="/dev/hidraw1"):
        mouse.connect()
    assert fake.opened[0].closed and not mouse.is_connected
