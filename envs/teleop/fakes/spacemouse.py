"""A fake ``pyspacemouse`` 2.x module: scripted SpaceMouse states behind the real API's calls.

It offers what :class:`~rmb_lerobot.envs.teleop.spacemouse.SpaceMouseDevice` calls, with the
signatures of pyspacemouse 2.1 (``pyspacemouse/api.py``): ``open(callback=None, ...,
nonblocking=True, device=None, device_index=0, device_spec=None, axis_convention=None)``,
``open_by_path(path, callback=None, ..., nonblocking=True, device_spec=None,
axis_convention=None)``, ``AxisConvention`` (``legacy``, ``hid``, ``hid_z_up``) and a device
whose ``read()`` returns a state with ``t, x, y, z, roll, pitch, yaw, buttons`` and which has
``close()``.

A script is a list of states in the *HID* frame (what the hardware reports: +x right, +y
towards the user, +z down, rotations about those axes); the fake hands them out in the
convention the caller asked for, with pyspacemouse's own remaps (``config_helpers.py``
``_HID_TO_CONVENTION``: LEGACY is ``x, -y, -z, -pitch, -roll, yaw`` of HID). Each ``read()``
returns the next state; the last one repeats once the script is used up. Install it with
``monkeypatch.setitem(sys.modules, "pyspacemouse", FakePySpaceMouse(...))``, or for another
process (a LeRobot CLI) write an importable stand-in with :func:`write_module`.
"""

from __future__ import annotations

import enum
import json
import types
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path

AXES = ("x", "y", "z", "roll", "pitch", "yaw")
DEFAULT_PATH = "/dev/hidraw0"


class AxisConvention(str, enum.Enum):  # noqa: UP042  (as pyspacemouse declares it)
    """pyspacemouse 2.x's conventions (the ones the fake converts to)."""

    LEGACY = "legacy"
    HID = "hid"
    HID_Z_UP = "hid_z_up"


# Output axis <- (HID axis, sign), as pyspacemouse 2.1 defines each convention.
_FROM_HID: dict[AxisConvention, dict[str, tuple[str, int]]] = {
    AxisConvention.HID: {axis: (axis, 1) for axis in AXES},
    AxisConvention.LEGACY: {
        "x": ("x", 1),
        "y": ("y", -1),
        "z": ("z", -1),
        "roll": ("pitch", -1),
        "pitch": ("roll", -1),
        "yaw": ("yaw", 1),
    },
    AxisConvention.HID_Z_UP: {
        "x": ("x", 1),
        "y": ("y", -1),
        "z": ("z", -1),
        "roll": ("roll", 1),
        "pitch": ("pitch", -1),
        "yaw": ("yaw", -1),
    },
}


@dataclass
class FakeState:
    """A SpaceMouse state (pyspacemouse's ``SpaceMouseState`` fields), axes in [-1, 1]."""

    t: float = -1.0
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    roll: float = 0.0
    pitch: float = 0.0
    yaw: float = 0.0
    buttons: list[int] = field(default_factory=lambda: [0, 0])


def convert(state: FakeState, convention: AxisConvention | str | None) -> FakeState:
    """A HID-frame state in another convention (None: LEGACY, pyspacemouse's default).

    Args:
        state: The state as the hardware reports it.
        convention: The convention to express it in.

    Returns:
        A new state.
    """
    remap = _FROM_HID[AxisConvention(convention or AxisConvention.LEGACY)]
    values = {out: sign * getattr(state, src) for out, (src, sign) in remap.items()}
    return FakeState(t=state.t, buttons=list(state.buttons), **values)


class FakeDevice:
    """One opened SpaceMouse: ``read()`` walks its script, ``close()`` marks it closed."""

    def __init__(self, path: str, script: Sequence[FakeState], convention: AxisConvention):
        self.path = path
        self.convention = convention
        self._script = list(script) or [FakeState()]
        self._index = 0
        self.reads = 0
        self.closed = False

    def read(self) -> FakeState:
        """The next scripted state, in the convention the device was opened with."""
        if self.closed:
            raise OSError(f"{self.path}: device is closed")
        state = self._script[min(self._index, len(self._script) - 1)]
        self._index += 1
        self.reads += 1
        return convert(state, self.convention)

    def close(self) -> None:
        """Close the device."""
        self.closed = True


class FakePySpaceMouse(types.ModuleType):
    """Stands in for the ``pyspacemouse`` module.

    Args:
        scripts: HID-frame states per device path; the first path is what ``open()`` (no
            path) finds.
        hidapi_missing: Behave as pyspacemouse does without the system hidapi library
            (``open`` raises ``RuntimeError("HID API is probably not installed...")``).

    Attributes:
        opened: Every device handed out, in order.
    """

    AxisConvention = AxisConvention

    def __init__(
        self, scripts: Mapping[str, Sequence[FakeState]], hidapi_missing: bool = False
    ) -> None:
        super().__init__("pyspacemouse")
        self.__version__ = "2.1.0"
        self.scripts = dict(scripts)
        self.hidapi_missing = hidapi_missing
        self.opened: list[FakeDevice] = []

    def _check_hidapi(self) -> None:
        if self.hidapi_missing:
            raise RuntimeError(
                "HID API is probably not installed. See https://spacemouse.kubaandrysek.cz "
                "for details."
            )

    def open(
        self,
        callback: Callable | None = None,
        dof_callback: Callable | None = None,
        dof_callbacks: Sequence | None = None,
        button_callback: Callable | None = None,
        button_callbacks: Sequence | None = None,
        nonblocking: bool = True,
        device: str | None = None,
        device_index: int = 0,
        device_spec: object | None = None,
        axis_convention: AxisConvention | None = None,
    ) -> FakeDevice:
        """The ``device_index``-th scripted device (the first when out of range, as 2.1)."""
        self._check_hidapi()
        if not self.scripts:
            raise RuntimeError("No connected or supported devices found.")
        paths = list(self.scripts)
        path = paths[device_index if device_index < len(paths) else 0]
        return self._hand_out(path, axis_convention)

    def open_by_path(
        self,
        path: str,
        callback: Callable | None = None,
        dof_callback: Callable | None = None,
        dof_callbacks: Sequence | None = None,
        button_callback: Callable | None = None,
        button_callbacks: Sequence | None = None,
        nonblocking: bool = True,
        device_spec: object | None = None,
        axis_convention: AxisConvention | None = None,
    ) -> FakeDevice:
        """The device scripted for ``path``; ``FileNotFoundError`` for any other path."""
        self._check_hidapi()
        if str(path) not in self.scripts:
            raise FileNotFoundError(f"Device path '{path}' does not exist.")
        return self._hand_out(str(path), axis_convention)

    def _hand_out(self, path: str, convention: AxisConvention | None) -> FakeDevice:
        device = FakeDevice(
            path, self.scripts[path], AxisConvention(convention or AxisConvention.LEGACY)
        )
        self.opened.append(device)
        return device


SHIM = '''"""Stand-in for pyspacemouse written by rmb_lerobot's test double (see {source})."""
import json
import sys
from pathlib import Path

from rmb_lerobot.envs.teleop.fakes.spacemouse import FakePySpaceMouse, FakeState

_scripts = json.loads((Path(__file__).parent / "pyspacemouse_script.json").read_text())
sys.modules[__name__] = FakePySpaceMouse(
    {{path: [FakeState(**state) for state in states] for path, states in _scripts.items()}}
)
'''


def write_module(directory: Path, scripts: Mapping[str, Sequence[FakeState]]) -> Path:
    """Write an importable ``pyspacemouse`` stand-in for another process (a LeRobot CLI).

    Put ``directory`` first on the child's ``PYTHONPATH``: its ``import pyspacemouse`` then
    gets a :class:`FakePySpaceMouse` playing ``scripts`` (saved beside it as JSON).

    Args:
        directory: Where to write ``pyspacemouse.py`` and its script.
        scripts: HID-frame states per device path.

    Returns:
        The module's path.
    """
    directory.mkdir(parents=True, exist_ok=True)
    data = {path: [asdict(state) for state in states] for path, states in scripts.items()}
    (directory / "pyspacemouse_script.json").write_text(json.dumps(data))
    module = directory / "pyspacemouse.py"
    module.write_text(SHIM.format(source=__name__))
    return module
