"""3Dconnexion SpaceMouse as a Cartesian input device (RMB's ``SpacemouseInputDevice``).

Read with ``pyspacemouse`` 2.x (extra ``spacemouse``), which needs the system hidapi library
(``libhidapi-hidraw0`` on Debian/Ubuntu) and read access to ``/dev/hidraw*`` (a udev rule).
One device per arm: :attr:`SpaceMouseConfig.paths` lists one ``/dev/hidrawN`` per arm and
each is opened with ``open_by_path`` (RMB pins pyspacemouse 1.1.4 because 2.x dropped the
``path`` argument of ``open``, its issue #45); with no paths the first device found drives
arm 0.

RMB's mapping, per control step, with the state in pyspacemouse's legacy axes (those of
1.1.4, what RMB was written against)::

    dpos = pos_scale · (-y, x, z)                    pos_scale = 1e-2 m
    drpy = rpy_scale · (-roll, -pitch, -2 · yaw)     rpy_scale = 5e-3 rad
    dgripper = +gripper_scale if only the first button is pressed,
               -gripper_scale if only the last one is        gripper_scale = 5

Devices are opened in the raw HID convention (not deprecated, unlike LEGACY) and turned into
the legacy axes here, with pyspacemouse's own definition of LEGACY: ``(x, -y, -z, -pitch,
-roll, yaw)`` of HID. Each step reads the device several times (RMB: 10), because a read
returns one queued HID report and only the last one is the current state.

Construct with a :class:`SpaceMouseConfig` (the teleop loop does this by module path,
``rmb_lerobot.envs.teleop.spacemouse.SpaceMouseDevice``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from rmb_lerobot.envs.teleop.device import CartesianDelta, DeviceReading, InputDevice

POS_SCALE = 1e-2
RPY_SCALE = 5e-3
GRIPPER_SCALE = 5.0
READS_PER_STEP = 10
HIDAPI_HINT = (
    "pyspacemouse needs the system hidapi library (Debian/Ubuntu: sudo apt install "
    "libhidapi-hidraw0; macOS: brew install hidapi) and read access to /dev/hidraw* (on "
    'Linux a udev rule, e.g. KERNEL=="hidraw*", ATTRS{idVendor}=="256f", MODE="0666")'
)
INSTALL_HINT = (
    "the SpaceMouse needs pyspacemouse 2.x: pip install 'lerobot_env_rmb[spacemouse]' "
    "(or uv sync --extra spacemouse); " + HIDAPI_HINT
)


@dataclass(frozen=True)
class SpaceMouseConfig:
    """SpaceMouse device settings (RMB's defaults).

    Attributes:
        paths: One ``/dev/hidrawN`` per arm, in record order; empty: the first SpaceMouse
            found drives arm 0.
        pos_scale: Metres per step at full deflection.
        rpy_scale: Radians per step at full deflection (yaw: twice this).
        gripper_scale: Gripper command units per step while a button is held.
        reads_per_step: Reads per step; the last one is used.
    """

    paths: tuple[str, ...] = ()
    pos_scale: float = POS_SCALE
    rpy_scale: float = RPY_SCALE
    gripper_scale: float = GRIPPER_SCALE
    reads_per_step: int = READS_PER_STEP

    def __post_init__(self) -> None:
        if len(set(self.paths)) != len(self.paths):
            raise ValueError(f"SpaceMouse paths must be distinct (one per arm), got {self.paths}")
        if self.reads_per_step < 1:
            raise ValueError(f"reads_per_step must be >= 1, got {self.reads_per_step}")
        for name in ("pos_scale", "rpy_scale", "gripper_scale"):
            if not getattr(self, name) >= 0:
                raise ValueError(f"SpaceMouse {name} must be >= 0, got {getattr(self, name)}")


def legacy_axes(state: Any) -> np.ndarray:
    """A HID-convention state as pyspacemouse's legacy (1.x) ``x, y, z, roll, pitch, yaw``.

    Args:
        state: A ``SpaceMouseState`` read in ``AxisConvention.HID``.

    Returns:
        The six legacy axis values.
    """
    return np.array(
        [state.x, -state.y, -state.z, -state.pitch, -state.roll, state.yaw], dtype=np.float64
    )


def rmb_delta(legacy: np.ndarray, buttons: list[int], config: SpaceMouseConfig) -> CartesianDelta:
    """RMB's step from legacy axes and the buttons.

    Args:
        legacy: ``x, y, z, roll, pitch, yaw`` in legacy axes.
        buttons: Button states (0/1), first to last.
        config: The scales.

    Returns:
        The pose and gripper change for one step.
    """
    x, y, z, roll, pitch, yaw = legacy
    dpos = config.pos_scale * np.array([-y, x, z])
    drpy = config.rpy_scale * np.array([-roll, -pitch, -2.0 * yaw])
    dgripper = 0.0
    if buttons:
        first, last = buttons[0] > 0, buttons[-1] > 0
        if first and not last:
            dgripper = config.gripper_scale
        elif last and not first:
            dgripper = -config.gripper_scale
    return CartesianDelta(dpos=dpos, drpy=drpy, dgripper=dgripper)


class SpaceMouseDevice(InputDevice):
    """One SpaceMouse per arm, each giving RMB's :class:`CartesianDelta` per step.

    Args:
        config: Device paths and scales.
    """

    name = "spacemouse"

    def __init__(self, config: SpaceMouseConfig | None = None):
        self.config = config or SpaceMouseConfig()
        self._devices: list[Any] = []

    @property
    def is_connected(self) -> bool:
        """Whether the devices are open."""
        return bool(self._devices)

    def connect(self) -> None:
        """Open every device (``open_by_path`` per arm, or the first one found).

        Raises:
            ImportError: pyspacemouse is not installed (the message names the extra and
                the system hidapi library).
            ConnectionError: hidapi is missing, or a device is absent or unsupported (the
                message names the path).
        """
        if self._devices:
            return
        try:
            import pyspacemouse
        except ImportError as error:
            raise ImportError(INSTALL_HINT) from error
        hid = pyspacemouse.AxisConvention.HID
        try:
            if self.config.paths:
                for path in self.config.paths:
                    self._devices.append(self._open(pyspacemouse, path, hid))
            else:
                self._devices.append(self._open(pyspacemouse, None, hid))
        except BaseException:
            self.close()
            raise

    @staticmethod
    def _open(pyspacemouse: Any, path: str | None, convention: Any) -> Any:
        where = path or "the first SpaceMouse found"
        try:
            if path is None:
                device = pyspacemouse.open(axis_convention=convention)
            else:
                device = pyspacemouse.open_by_path(path, axis_convention=convention)
        except (FileNotFoundError, ValueError) as error:
            raise ConnectionError(f"SpaceMouse at {where}: {error}") from error
        except (AttributeError, OSError, RuntimeError) as error:
            # easyhid without the system library fails with AttributeError / OSError;
            # pyspacemouse turns some of those into "HID API is probably not installed".
            raise ConnectionError(f"SpaceMouse at {where}: {error}; {HIDAPI_HINT}") from error
        if device is None:
            raise ConnectionError(f"SpaceMouse at {where}: pyspacemouse opened no device")
        return device

    def read(self) -> DeviceReading:
        """Each arm's step from the newest state of its device.

        Returns:
            A :class:`CartesianDelta` per arm.

        Raises:
            RuntimeError: Not connected.
        """
        if not self._devices:
            raise RuntimeError("SpaceMouse is not connected; call connect() first")
        arms: dict[int, CartesianDelta] = {}
        for index, device in enumerate(self._devices):
            state = None
            for _ in range(self.config.reads_per_step):
                state = device.read()
            arms[index] = rmb_delta(legacy_axes(state), list(state.buttons), self.config)
        return DeviceReading(arms=arms)

    def close(self) -> None:
        """Close every device (safe to call twice)."""
        devices, self._devices = self._devices, []
        for device in devices:
            device.close()
