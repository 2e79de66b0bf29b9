"""A keyboard as a contact sensor: 2 x 3 key states on the gripper fingers, as a grid.

The paper's "Hardware Extension for Contact Sensing" mounts a compact programmable keyboard
with 2 x 3 keys on the two fingers of a parallel gripper (a Robotiq 2F-140 with a Sanwa
400-SKB081) and records which keys are pressed as a grid contact observation; a Diffusion
Policy trained with it re-grasped an object pulled out of the gripper. RMB's real envs read the
keyboard's raw HID reports and map the keys F14, F15, F16 to row 0 and F17, F18, F19 to row 1
(``RealEnvBase.get_intensity_tactile_data``); :data:`RMB_KEY_GRID` is that layout.

Here the grid is read through a small driver interface (:class:`KeyStateDriver`: which keys
are down now), so a real env plugs in :class:`EvdevKeyDriver` (Linux input events; the
optional extra ``keyboard``) and tests use :class:`FakeKeyboard`. :class:`KeyboardContactGrid`
polls the driver on its own thread, so an env step never waits on USB, and keeps a watchdog:
a reading older than ``max_age_s`` (device unplugged, driver hung) is *stale*, and what
:meth:`KeyboardContactGrid.observation` then does is the ``on_stale`` policy (raise by
default: a silently frozen or zeroed contact reading would teach or drive a policy wrong).
A lost device is reopened every ``reopen_after_s``.

The observation is ``contact_grid``: ``uint8`` of shape ``(rows, cols)`` (``(2, 3)``), 1 where
the key of that cell is pressed; :class:`ContactGridObservation` adds it to an env's dict
observation (LeRobot passes such a key through as ``observation.contact_grid``).
"""

from __future__ import annotations

import contextlib
import json
import logging
import re
import sys
import threading
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal, Protocol, runtime_checkable

import gymnasium as gym
import numpy as np

logger = logging.getLogger(__name__)

__all__ = [
    "OBSERVATION_KEY",
    "RMB_KEY_GRID",
    "ContactGridObservation",
    "ContactReading",
    "EvdevKeyDriver",
    "FakeKeyboard",
    "KeyMap",
    "KeyStateDriver",
    "KeyboardContactGrid",
    "SensorStaleError",
]

OBSERVATION_KEY = "contact_grid"
RMB_KEY_GRID: tuple[tuple[str, ...], ...] = (
    ("KEY_F14", "KEY_F15", "KEY_F16"),  # row 0: RMB's key indices 0..2
    ("KEY_F17", "KEY_F18", "KEY_F19"),  # row 1: RMB's key indices 3..5
)
"""RMB's cell of each key: index ``i`` of F14..F19 is cell ``(i // 3, i % 3)``."""

_KEY_NAME = re.compile(r"^(KEY|BTN)_[A-Z0-9_]+$")  # Linux input event code names (evdev's)


# ------------------------------------------------------------------ key map
@dataclass(frozen=True)
class KeyMap:
    """Which key is which grid cell: ``grid[row][col]`` is a Linux key name (``KEY_F14``).

    Build it from a config with :meth:`from_config` / :meth:`from_file`: either
    ``{"grid": [["KEY_F14", "KEY_F15", "KEY_F16"], [...]]}`` or one entry per key,
    ``{"KEY_F14": [0, 0], ...}`` (every cell exactly once).
    """

    grid: tuple[tuple[str, ...], ...] = RMB_KEY_GRID
    cells: dict[str, tuple[int, int]] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        grid = tuple(tuple(row) for row in self.grid)
        object.__setattr__(self, "grid", grid)
        if not grid or not grid[0]:
            raise ValueError("key map: the grid needs at least one row and one column")
        if any(len(row) != len(grid[0]) for row in grid):
            raise ValueError(f"key map: rows differ in length {[len(r) for r in grid]}")
        cells: dict[str, tuple[int, int]] = {}
        for r, row in enumerate(grid):
            for c, name in enumerate(row):
                if not isinstance(name, str) or not _KEY_NAME.match(name):
                    raise ValueError(
                        f"key map: cell ({r}, {c}) is {name!r}; expected a Linux key name "
                        "such as 'KEY_F14' or 'BTN_0'"
                    )
                if name in cells:
                    raise ValueError(f"key map: {name} is in cells {cells[name]} and ({r}, {c})")
                cells[name] = (r, c)
        object.__setattr__(self, "cells", cells)

    @property
    def shape(self) -> tuple[int, int]:
        return len(self.grid), len(self.grid[0])

    def grid_from(self, pressed: Iterable[str]) -> np.ndarray:
        """The ``uint8`` grid for a set of pressed key names (unmapped keys are ignored)."""
        grid = np.zeros(self.shape, dtype=np.uint8)
        for name in pressed:
            cell = self.cells.get(name)
            if cell is not None:
                grid[cell] = 1
        return grid

    @classmethod
    def from_config(cls, config: Mapping[str, Any], source: str = "key map") -> KeyMap:
        if "grid" in config:
            if set(config) != {"grid"}:
                raise ValueError(f"{source}: 'grid' goes alone, got {sorted(config)}")
            return cls(tuple(tuple(row) for row in config["grid"]))
        cells = {}
        for name, cell in config.items():
            if not (
                isinstance(cell, Sequence)
                and len(cell) == 2
                and all(isinstance(i, int) for i in cell)
            ):
                raise ValueError(f"{source}: {name} -> {cell!r}; expected a [row, col] pair")
            cells[name] = (cell[0], cell[1])
        if not cells:
            raise ValueError(f"{source}: empty; give 'grid' or KEY_NAME: [row, col] entries")
        rows = 1 + max(r for r, _ in cells.values())
        cols = 1 + max(c for _, c in cells.values())
        grid: list[list[str | None]] = [[None] * cols for _ in range(rows)]
        for name, (r, c) in cells.items():
            if r < 0 or c < 0:
                raise ValueError(f"{source}: {name} -> ({r}, {c}); cells count from 0")
            if grid[r][c] is not None:
                raise ValueError(f"{source}: cell ({r}, {c}) has {grid[r][c]} and {name}")
            grid[r][c] = name
        empty = [(r, c) for r in range(rows) for c in range(cols) if grid[r][c] is None]
        if empty:
            raise ValueError(f"{source}: cells {empty} have no key")
        return cls(tuple(tuple(row) for row in grid))  # type: ignore[arg-type]

    @classmethod
    def from_file(cls, path: str | Path) -> KeyMap:
        """A key map from a JSON or YAML file (see :meth:`from_config`)."""
        path = Path(path)
        text = path.read_text(encoding="utf-8")
        try:
            if path.suffix in (".yaml", ".yml"):
                import yaml

                config = yaml.safe_load(text)
            else:
                config = json.loads(text)
        except ValueError as err:  # JSONDecodeError and yaml.YAMLError's parse errors
            raise ValueError(f"key map {path}: cannot parse: {err}") from err
        if not isinstance(config, Mapping):
            raise ValueError(f"key map {path}: expected a mapping, got {type(config).__name__}")
        return cls.from_config(config, source=f"key map {path}")


# ------------------------------------------------------------------ drivers
@runtime_checkable
class KeyStateDriver(Protocol):
    """Reads which keys of one keyboard are down. ``pressed`` raises ``OSError`` when the
    device is gone; it may block (the sensor calls it on its own thread, and treats any
    exception as a lost device to reopen)."""

    name: str

    def open(self) -> None: ...

    def pressed(self) -> frozenset[str]: ...

    def close(self) -> None: ...


def _import_evdev():
    try:
        import evdev
    except ImportError as err:
        where = "" if sys.platform.startswith("linux") else f" (this is {sys.platform})"
        raise ImportError(
            "the keyboard contact sensor's evdev driver needs the 'evdev' package, Linux "
            f"only{where}: pip install 'lerobot_env_rmb[keyboard]'"
        ) from err
    return evdev


class EvdevKeyDriver:
    """A keyboard through Linux input events (``/dev/input/eventN``, or a stable
    ``/dev/input/by-id/...-event-kbd`` link). ``grab`` (default) takes the device exclusively,
    so finger contacts do not type F14.. into other programs. The process needs read access
    to the device (the ``input`` group, or a udev rule)."""

    def __init__(self, device: str | Path, grab: bool = True):
        self.device = str(device)
        self.name = f"evdev:{self.device}"
        self.grab = grab
        self._dev = None
        self._names: dict[int, tuple[str, ...]] = {}

    def open(self) -> None:
        evdev = _import_evdev()
        try:
            dev = evdev.InputDevice(self.device)
        except OSError as err:
            raise OSError(f"{self.name}: cannot open the keyboard: {err}") from err
        if self.grab:
            dev.grab()
        self._dev = dev
        self._names = {}
        for table in (evdev.ecodes.KEY, evdev.ecodes.BTN):
            for code, names in table.items():
                names = (names,) if isinstance(names, str) else tuple(names)
                self._names[code] = self._names.get(code, ()) + names

    def pressed(self) -> frozenset[str]:
        if self._dev is None:
            raise OSError(f"{self.name}: not open")
        codes = self._dev.active_keys()  # EVIOCGKEY: the kernel's key state, no event backlog
        return frozenset(name for code in codes for name in self._names.get(code, ()))

    def close(self) -> None:
        dev, self._dev = self._dev, None
        if dev is not None:
            try:
                if self.grab:
                    dev.ungrab()
            except OSError:
                pass  # already gone
            dev.close()


class FakeKeyboard:
    """A test double for :class:`KeyStateDriver`: keys are pressed and released by hand,
    and the device can be unplugged (``pressed`` raises) or hung (``pressed`` blocks)."""

    def __init__(self, name: str = "fake-keyboard"):
        self.name = name
        self.opens = self.closes = 0
        self.is_open = False
        self._keys: set[str] = set()
        self._lock = threading.Lock()
        self._unplugged: OSError | None = None
        self._running = threading.Event()
        self._running.set()

    def press(self, *names: str) -> None:
        with self._lock:
            self._keys.update(names)

    def release(self, *names: str) -> None:
        with self._lock:
            self._keys.difference_update(names)

    def unplug(self, error: OSError | None = None) -> None:
        """``open`` and ``pressed`` raise ``error`` until :meth:`plug_in`."""
        self._unplugged = error or OSError(19, "No such device")

    def plug_in(self) -> None:
        self._unplugged = None

    def hang(self) -> None:
        """``pressed`` blocks until :meth:`resume`."""
        self._running.clear()

    def resume(self) -> None:
        self._running.set()

    def open(self) -> None:
        self.opens += 1
        if self._unplugged is not None:
            raise self._unplugged
        self.is_open = True

    def pressed(self) -> frozenset[str]:
        self._running.wait()
        if self._unplugged is not None:
            self.is_open = False
            raise self._unplugged
        if not self.is_open:
            raise OSError(f"{self.name}: not open")
        with self._lock:
            return frozenset(self._keys)

    def close(self) -> None:
        self.closes += 1
        self.is_open = False


# ------------------------------------------------------------------ the sensor
class SensorStaleError(RuntimeError):
    """The contact grid has not been read for longer than the sensor's ``max_age_s``."""


@dataclass(frozen=True)
class ContactReading:
    grid: np.ndarray  # uint8 (rows, cols), the last grid read
    age_s: float  # since that read (inf: none yet)
    stale: bool  # age_s > max_age_s
    error: str | None  # the driver's last error, if its last attempt failed


StalePolicy = Literal["raise", "hold", "zeros"]


class KeyboardContactGrid:
    """The contact grid of a keyboard on the gripper, polled on a background thread.

    ``poll_hz``: driver reads per second (200: well above RMB's 50 Hz real-robot loop);
    ``max_age_s``: a reading older than this is stale; ``on_stale``: what :meth:`observation`
    does then (``"raise"`` :class:`SensorStaleError`, ``"hold"`` the last grid, ``"zeros"``
    report no contact); ``reopen_after_s``: how often a lost device is reopened.

    >>> with KeyboardContactGrid(EvdevKeyDriver("/dev/input/event7")) as sensor:  # doctest: +SKIP
    ...     sensor.observation()  # array([[0, 1, 0], [0, 0, 0]], dtype=uint8)
    """

    def __init__(
        self,
        driver: KeyStateDriver,
        key_map: KeyMap | None = None,
        *,
        poll_hz: float = 200.0,
        max_age_s: float = 0.1,
        on_stale: StalePolicy = "raise",
        reopen_after_s: float = 1.0,
        clock: Callable[[], float] = time.monotonic,
    ):
        if on_stale not in ("raise", "hold", "zeros"):
            raise ValueError(f"on_stale must be 'raise', 'hold' or 'zeros', got {on_stale!r}")
        if poll_hz <= 0 or max_age_s <= 0:
            raise ValueError(f"poll_hz and max_age_s must be > 0, got {poll_hz}, {max_age_s}")
        self.driver = driver
        self.key_map = key_map or KeyMap()
        self.poll_s = 1.0 / poll_hz
        self.max_age_s = max_age_s
        self.on_stale = on_stale
        self.reopen_after_s = reopen_after_s
        self.clock = clock
        self._lock = threading.Lock()
        self._grid = np.zeros(self.key_map.shape, dtype=np.uint8)
        self._stamp: float | None = None
        self._error: str | None = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    @property
    def shape(self) -> tuple[int, int]:
        return self.key_map.shape

    def observation_space(self) -> gym.spaces.Box:
        return gym.spaces.Box(0, 1, self.shape, dtype=np.uint8)

    # ------------------------------------------------------------------ lifecycle
    def __enter__(self) -> KeyboardContactGrid:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def start(self, first_reading_timeout_s: float = 1.0) -> None:
        """Open the device (its errors surface here) and start polling; waits up to
        ``first_reading_timeout_s`` for the first reading."""
        if self._thread is not None:
            return
        self.driver.open()
        self._stop.clear()
        self._thread = threading.Thread(
            target=self._poll, name=f"contact:{self.driver.name}", daemon=True
        )
        self._thread.start()
        deadline = time.monotonic() + first_reading_timeout_s
        while self._stamp is None and time.monotonic() < deadline:
            time.sleep(min(self.poll_s, 0.01))

    def close(self) -> None:
        thread, self._thread = self._thread, None
        if thread is not None:
            self._stop.set()
            thread.join(timeout=max(1.0, 5 * self.poll_s))
            if thread.is_alive():
                logger.warning(
                    "%s: the driver is blocked; leaving its thread behind", self.driver.name
                )
        try:
            self.driver.close()
        except OSError as err:
            logger.warning("%s: close: %s", self.driver.name, err)

    def _poll(self) -> None:
        next_reopen = 0.0
        opened = True
        while not self._stop.is_set():
            try:
                if not opened:
                    if time.monotonic() < next_reopen:
                        self._stop.wait(self.poll_s)
                        continue
                    next_reopen = time.monotonic() + self.reopen_after_s
                    with contextlib.suppress(Exception):
                        self.driver.close()
                    self.driver.open()
                    opened = True
                    logger.info("%s: reopened", self.driver.name)
                grid = self.key_map.grid_from(self.driver.pressed())
            except Exception as err:  # OSError: unplugged; anything else: a driver bug
                if opened:
                    logger.warning(
                        "%s: %s; reopening every %.1f s", self.driver.name, err, self.reopen_after_s
                    )
                    next_reopen = time.monotonic() + self.reopen_after_s
                opened = False
                with self._lock:
                    self._error = str(err) or type(err).__name__
                continue
            with self._lock:
                self._grid = grid
                self._stamp = self.clock()
                self._error = None
            self._stop.wait(self.poll_s)

    # ------------------------------------------------------------------ readings
    def read(self) -> ContactReading:
        """The latest grid with its age; never raises, never waits on the device."""
        with self._lock:
            grid, stamp, error = self._grid.copy(), self._stamp, self._error
        age = float("inf") if stamp is None else max(0.0, self.clock() - stamp)
        return ContactReading(grid, age, age > self.max_age_s, error)

    def observation(self) -> np.ndarray:
        """The grid for an env observation, with the ``on_stale`` policy applied."""
        reading = self.read()
        if not reading.stale:
            return reading.grid
        if self.on_stale == "hold":
            return reading.grid
        if self.on_stale == "zeros":
            return np.zeros(self.shape, dtype=np.uint8)
        running = self._thread is not None and self._thread.is_alive()
        raise SensorStaleError(
            f"{self.driver.name}: contact grid is {reading.age_s:.3f} s old (max_age_s "
            f"{self.max_age_s}); last error: {reading.error or 'none (the driver is slow or hung)'}"
            f"{'' if running else '; the sensor is not running (start() it)'}"
        )


# ------------------------------------------------------------------ env wrapper
class ContactGridObservation(gym.ObservationWrapper):
    """Adds ``contact_grid`` (from a started :class:`KeyboardContactGrid`) to a dict
    observation; closing the wrapper closes the sensor."""

    def __init__(self, env: gym.Env, sensor: KeyboardContactGrid, key: str = OBSERVATION_KEY):
        super().__init__(env)
        if not isinstance(env.observation_space, gym.spaces.Dict):
            raise TypeError(
                f"{key}: the env's observation space must be a Dict, got {env.observation_space}"
            )
        if key in env.observation_space.spaces:
            raise ValueError(f"the env already observes {key!r}")
        self.sensor = sensor
        self.key = key
        self.observation_space = gym.spaces.Dict(
            {**env.observation_space.spaces, key: sensor.observation_space()}
        )

    def observation(self, observation: dict) -> dict:
        return {**observation, self.key: self.sensor.observation()}

    def close(self) -> None:
        self.sensor.close()
        super().close()
