"""The keyboard contact grid, with the FakeKeyboard test double (evdev is an optional extra)."""

from __future__ import annotations

import json
import sys
import time
import types

import gymnasium as gym
import numpy as np
import pytest

from rmb_lerobot.envs.sensors.keyboard_contact import (
    OBSERVATION_KEY,
    RMB_KEY_GRID,
    ContactGridObservation,
    EvdevKeyDriver,
    FakeKeyboard,
    KeyboardContactGrid,
    KeyMap,
    KeyStateDriver,
    SensorStaleError,
)


def eventually(condition, timeout: float = 5.0) -> None:
    """Wait for the polling thread (at 200 Hz a change shows within a few ms)."""
    deadline = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < deadline, "condition not met in time"
        time.sleep(0.005)


@pytest.fixture
def keyboard() -> FakeKeyboard:
    return FakeKeyboard()


@pytest.fixture
def sensor(keyboard):
    # max_age_s well above the 5 ms poll period, so a loaded test machine does not go stale.
    grid = KeyboardContactGrid(keyboard, max_age_s=0.25, reopen_after_s=0.05)
    with grid:
        yield grid
    assert not keyboard.is_open  # closed with the sensor


# ------------------------------------------------------------------ key map
def test_default_key_map_is_rmbs_f14_to_f19_layout():
    key_map = KeyMap()
    assert key_map.shape == (2, 3) and key_map.grid == RMB_KEY_GRID
    # RMB: key index i of F14..F19 goes to cell (i // 3, i % 3).
    for i, key in enumerate(f"KEY_F{n}" for n in range(14, 20)):
        assert key_map.cells[key] == (i // 3, i % 3)
    grid = key_map.grid_from({"KEY_F15", "KEY_F19", "KEY_A"})  # unmapped keys are ignored
    np.testing.assert_array_equal(grid, [[0, 1, 0], [0, 0, 1]])
    assert grid.dtype == np.uint8


def test_key_map_configs_both_forms_and_files(tmp_path):
    by_grid = KeyMap.from_config({"grid": [["KEY_1", "KEY_2"], ["KEY_3", "KEY_4"]]})
    by_key = KeyMap.from_config(
        {"KEY_4": [1, 1], "KEY_1": [0, 0], "KEY_2": [0, 1], "KEY_3": [1, 0]}
    )
    assert by_grid == by_key and by_grid.shape == (2, 2)

    path = tmp_path / "fingers.json"
    path.write_text(json.dumps({"grid": [list(row) for row in reversed(RMB_KEY_GRID)]}))
    swapped = KeyMap.from_file(path)  # e.g. the keyboard mounted the other way round
    np.testing.assert_array_equal(swapped.grid_from({"KEY_F14"}), [[0, 0, 0], [1, 0, 0]])
    yaml_path = tmp_path / "fingers.yaml"
    yaml_path.write_text("KEY_F14: [0, 0]\nKEY_F17: [1, 0]\n")
    assert KeyMap.from_file(yaml_path).grid == (("KEY_F14",), ("KEY_F17",))


@pytest.mark.parametrize(
    ("config", "message"),
    [
        ({"grid": [["KEY_F14", "KEY_F15"], ["KEY_F16"]]}, "rows differ"),
        ({"grid": [["KEY_F14", "KEY_F14"]]}, "KEY_F14 is in cells"),
        ({"grid": [["F14"]]}, "expected a Linux key name"),
        ({"grid": []}, "at least one row"),
        ({"KEY_F14": [0, 0], "KEY_F15": [0, 0]}, r"cell \(0, 0\) has KEY_F14 and KEY_F15"),
        ({"KEY_F14": [0, 0], "KEY_F15": [1, 1]}, r"cells \[\(0, 1\), \(1, 0\)\] have no key"),
        ({"KEY_F14": "0,0"}, "expected a \\[row, col\\] pair"),
        ({"KEY_F14": [0, -1]}, "count from 0"),
        ({}, "empty"),
    ],
)
def test_bad_key_maps_are_refused_naming_the_key_or_cell(config, message):
    with pytest.raises(ValueError, match=message):
        KeyMap.from_config(config)


def test_key_map_file_errors_name_the_file(tmp_path):
    path = tmp_path / "broken.json"
    path.write_text("{not json")
    with pytest.raises(ValueError, match=r"broken\.json: cannot parse"):
        KeyMap.from_file(path)
    path.write_text('["KEY_F14"]')
    with pytest.raises(ValueError, match=r"broken\.json: expected a mapping"):
        KeyMap.from_file(path)


# ------------------------------------------------------------------ sensor
def test_the_grid_follows_the_keys(keyboard, sensor):
    assert isinstance(keyboard, KeyStateDriver)
    np.testing.assert_array_equal(sensor.observation(), np.zeros((2, 3)))
    keyboard.press("KEY_F14", "KEY_F18")  # left finger's first key, right finger's middle
    eventually(lambda: sensor.observation().sum() == 2)
    obs = sensor.observation()
    np.testing.assert_array_equal(obs, [[1, 0, 0], [0, 1, 0]])
    assert obs.dtype == np.uint8 and sensor.observation_space().contains(obs)
    keyboard.release("KEY_F14")
    eventually(lambda: sensor.observation()[0, 0] == 0)
    reading = sensor.read()
    assert not reading.stale and reading.age_s <= sensor.max_age_s and reading.error is None


def test_a_hung_driver_makes_the_reading_stale_and_the_observation_raise(keyboard, sensor):
    keyboard.press("KEY_F16")
    eventually(lambda: sensor.observation()[0, 2] == 1)
    keyboard.hang()
    eventually(lambda: sensor.read().stale)
    with pytest.raises(SensorStaleError, match=r"fake-keyboard: contact grid is .* s old"):
        sensor.observation()
    keyboard.resume()
    eventually(lambda: not sensor.read().stale)
    assert sensor.observation()[0, 2] == 1


@pytest.mark.parametrize(("policy", "expected"), [("hold", 1), ("zeros", 0)])
def test_stale_policies_hold_or_zero(keyboard, policy, expected):
    with KeyboardContactGrid(keyboard, max_age_s=0.25, on_stale=policy) as sensor:
        keyboard.press("KEY_F17")
        eventually(lambda: sensor.read().grid[1, 0] == 1)
        keyboard.hang()
        eventually(lambda: sensor.read().stale)
        assert sensor.observation()[1, 0] == expected
        keyboard.resume()


def test_an_unplugged_keyboard_is_stale_with_its_error_and_reopened_when_back(keyboard, sensor):
    keyboard.press("KEY_F19")
    eventually(lambda: sensor.observation()[1, 2] == 1)
    opens = keyboard.opens
    keyboard.unplug()
    eventually(lambda: sensor.read().stale)
    assert "No such device" in sensor.read().error
    with pytest.raises(SensorStaleError, match="No such device"):
        sensor.observation()
    eventually(lambda: keyboard.opens >= opens + 2)  # it keeps trying
    keyboard.release("KEY_F19")
    keyboard.plug_in()
    eventually(lambda: not sensor.read().stale)
    assert sensor.read().error is None and sensor.observation().sum() == 0


def test_open_errors_surface_at_start_and_unstarted_sensors_say_so(keyboard):
    keyboard.unplug(PermissionError(13, "Permission denied: /dev/input/event7"))
    with pytest.raises(PermissionError, match="Permission denied"):
        KeyboardContactGrid(keyboard).start()
    idle = KeyboardContactGrid(FakeKeyboard())
    assert idle.read().age_s == float("inf")
    with pytest.raises(SensorStaleError, match=r"not running \(start\(\) it\)"):
        idle.observation()


def test_bad_settings_are_refused(keyboard):
    with pytest.raises(ValueError, match="on_stale"):
        KeyboardContactGrid(keyboard, on_stale="ignore")
    with pytest.raises(ValueError, match="max_age_s"):
        KeyboardContactGrid(keyboard, max_age_s=0)


# ------------------------------------------------------------------ env wrapper
class ArmStub(gym.Env):
    """A dict-observation env standing in for a real robot env."""

    def __init__(self):
        self.observation_space = gym.spaces.Dict(
            {"agent_pos": gym.spaces.Box(-1.0, 1.0, (7,), dtype=np.float32)}
        )
        self.action_space = gym.spaces.Box(-1.0, 1.0, (7,), dtype=np.float32)

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        return {"agent_pos": np.zeros(7, dtype=np.float32)}, {}

    def step(self, action):
        return {"agent_pos": np.asarray(action, dtype=np.float32)}, 0.0, False, False, {}


def test_the_wrapper_adds_contact_grid_to_the_observation(keyboard):
    sensor = KeyboardContactGrid(keyboard, max_age_s=0.5)
    sensor.start()
    env = ContactGridObservation(ArmStub(), sensor)
    assert env.observation_space[OBSERVATION_KEY] == gym.spaces.Box(0, 1, (2, 3), dtype=np.uint8)
    obs, _ = env.reset(seed=0)
    assert env.observation_space.contains(obs) and obs[OBSERVATION_KEY].sum() == 0
    keyboard.press("KEY_F15")
    eventually(lambda: sensor.read().grid[0, 1] == 1)
    obs, *_ = env.step(env.action_space.sample())
    np.testing.assert_array_equal(obs[OBSERVATION_KEY], [[0, 1, 0], [0, 0, 0]])
    env.close()
    assert not keyboard.is_open
    with pytest.raises(ValueError, match="already observes"):
        ContactGridObservation(ContactGridObservation(ArmStub(), sensor), sensor)


# ------------------------------------------------------------------ evdev driver
def test_evdev_driver_without_evdev_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "evdev", None)  # as when the extra is not installed
    with pytest.raises(ImportError, match=r"pip install 'lerobot_env_rmb\[keyboard\]'"):
        EvdevKeyDriver("/dev/input/event7").open()


def test_evdev_driver_reads_key_names_and_grabs(monkeypatch):
    """Against a stand-in of evdev's API (InputDevice, active_keys, grab, ecodes tables)."""
    devices = []

    class InputDevice:
        def __init__(self, path):
            if path != "/dev/input/event7":
                raise FileNotFoundError(2, "No such file or directory", path)
            self.path, self.grabbed, self.closed = path, False, False
            devices.append(self)

        def active_keys(self):
            return [184, 30, 999]  # F14, A, and a code without a name

        def grab(self):
            self.grabbed = True

        def ungrab(self):
            self.grabbed = False

        def close(self):
            self.closed = True

    ecodes = types.SimpleNamespace(
        KEY={184: "KEY_F14", 30: "KEY_A"}, BTN={256: ["BTN_0", "BTN_MISC"]}
    )
    monkeypatch.setitem(
        sys.modules, "evdev", types.SimpleNamespace(InputDevice=InputDevice, ecodes=ecodes)
    )

    driver = EvdevKeyDriver("/dev/input/event7")
    with KeyboardContactGrid(driver, max_age_s=0.5) as sensor:
        assert devices[0].grabbed  # F14.. must not type into other programs
        eventually(lambda: sensor.read().grid[0, 0] == 1)
        np.testing.assert_array_equal(sensor.observation(), [[1, 0, 0], [0, 0, 0]])
    assert devices[0].closed and not devices[0].grabbed
    with pytest.raises(OSError, match="evdev:/dev/input/event9: cannot open the keyboard"):
        EvdevKeyDriver("/dev/input/event9").open()
