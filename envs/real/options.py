"""Options of the real backend, as RMB's real-env YAML spells them (plus ``driver``).

:class:`RealOptions` takes the keys of RMB's ``envs/configs/Real*DemoEnv.yaml`` as they are:
``robot_ip`` (dual: ``robot_ip_left``, ``robot_ip_right``) and ``camera_ids`` (camera name ->
RealSense serial), plus ``driver: sim | sdk``. Imports no simulator and no SDK.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from rmb_lerobot.envs.images import DEFAULT_IMAGE_SIZE, RMB_IMAGE_SIZE, check_image_size
from rmb_lerobot.envs.real.drivers.common import DRIVER_KINDS
from rmb_lerobot.envs.real.limits import CONTROL_PERIOD, WATCHDOG_TIMEOUT, WorkspaceBox

if TYPE_CHECKING:
    from lerobot.cameras import CameraConfig

    from rmb_lerobot.envs.robots import Robot

log = logging.getLogger(__name__)

LOOPBACK = "127.0.0.1"
UNSUPPORTED_RMB_KEYS = ("gelsight_ids", "pointcloud_camera_ids", "sanwa_keyboard_ids")
"""Keys of RMB's real-env YAMLs for sensors this package does not drive yet (warned, ignored)."""


@dataclass(frozen=True)
class RealOptions:
    """How the real backend reaches its robot and cameras.

    Attributes:
        driver: ``"sim"`` (each arm's MuJoCo twin on loopback: a dry run) or ``"sdk"`` (the
            arm at ``robot_ip`` through its vendor SDK).
        robot_ip: The arm's controller address (single-arm robots; RMB's key). No default:
            with ``sdk`` it must be written; with ``sim`` it defaults to 127.0.0.1.
        robot_ip_left: Left arm's address (dual robots).
        robot_ip_right: Right arm's address (dual robots).
        camera_ids: Camera name -> RealSense serial (RMB's ``camera_ids: {front, hand}``); with
            ``sim`` the names choose twin cameras (a name with ``hand`` in it renders that
            arm's wrist camera, any other the front view) and the serials are not used.
        camera_configs: LeRobot camera configs by name; replaces ``camera_ids`` when given.
        image_size: ``(width, height)`` of every camera (default: RMB's 640 x 480 with
            ``sdk``, 128 x 128 on the twin).
        camera_fps: Camera frame rate (a RealSense's 30).
        control_dt: Control period (s): RMB's 0.02 (50 Hz).
        reset_scale: ``v_lim`` scale of reset moves; ``None``: RMB's per robot (UR5e 0.3,
            xArm7 0.1).
        settle_s: RMB's pause before and after zeroing the wrench at reset (s).
        arrive_tolerance: After a reset move, wait until every arm joint is this close to
            home (rad) ...
        arrive_timeout_s: ... or this long (s), then go on with a warning.
        watchdog_timeout: Stop the arms when no step comes this long after the last one's
            period (s; armed from the end of each reset).
        tcp_box: A TCP workspace box for every arm, or ``None``.
        spin_s: The loop sleeps until this long before each tick, then spins (s): a sleep
            wakes late by up to a scheduler tick on a loaded machine.
        realtime_priority: Run the stepping thread under Linux's ``SCHED_FIFO`` at this
            priority (1..99) from its first reset until :meth:`close`, or ``None`` (the
            default) to leave scheduling alone. Needs ``CAP_SYS_NICE`` or an ``rtprio`` limit
            (:mod:`~rmb_lerobot.envs.real.realtime`); the error says how to allow it.
        gelsight_ids: RMB's key, not supported yet (warned, ignored).
        pointcloud_camera_ids: RMB's key, not supported yet (warned, ignored).
        sanwa_keyboard_ids: RMB's key, not supported yet (warned, ignored).

    Raises:
        ValueError: An unknown driver, a bad size or period.
    """

    driver: str = "sim"
    robot_ip: str | None = None
    robot_ip_left: str | None = None
    robot_ip_right: str | None = None
    camera_ids: Mapping[str, Any] | None = None
    camera_configs: Mapping[str, CameraConfig] | None = None
    image_size: tuple[int, int] | None = None
    camera_fps: int = 30
    control_dt: float = CONTROL_PERIOD
    reset_scale: float | None = None
    settle_s: float = 0.2
    arrive_tolerance: float = 0.01
    arrive_timeout_s: float = 3.0
    watchdog_timeout: float = WATCHDOG_TIMEOUT
    tcp_box: WorkspaceBox | None = None
    spin_s: float = 0.001
    realtime_priority: int | None = None
    gelsight_ids: Mapping[str, Any] | None = None
    pointcloud_camera_ids: Mapping[str, Any] | None = None
    sanwa_keyboard_ids: Mapping[str, Any] | None = None

    def __post_init__(self) -> None:
        if self.driver not in DRIVER_KINDS:
            raise ValueError(f"driver must be one of {DRIVER_KINDS}, got {self.driver!r}")
        size = self.image_size
        if size is None:
            size = RMB_IMAGE_SIZE if self.driver == "sdk" else DEFAULT_IMAGE_SIZE
        object.__setattr__(self, "image_size", check_image_size(size))
        if not 0 < self.control_dt <= 1.0:
            raise ValueError(f"control_dt must be in (0, 1] s, got {self.control_dt}")
        if self.settle_s < 0 or self.spin_s < 0 or self.camera_fps <= 0:
            raise ValueError("settle_s and spin_s must be >= 0, camera_fps > 0")
        if self.realtime_priority is not None and not 1 <= self.realtime_priority <= 99:
            raise ValueError(
                f"realtime_priority must be in 1..99 or None, got {self.realtime_priority}"
            )
        for key in UNSUPPORTED_RMB_KEYS:
            if getattr(self, key):
                log.warning("%s: not supported by this package yet; ignored", key)

    def hosts_for(self, robot: Robot) -> tuple[str, ...]:
        """Each arm's controller address, in arm order.

        Args:
            robot: The robot record.

        Returns:
            One address per arm.

        Raises:
            ValueError: A needed address is missing (``sdk``) or the wrong key was used.
        """
        if len(robot.arms) == 1:
            if self.robot_ip_left or self.robot_ip_right:
                raise ValueError(
                    f"{robot.name} has one arm: write robot_ip, not robot_ip_left/right"
                )
            names, given = ("robot_ip",), (self.robot_ip,)
        else:
            if self.robot_ip:
                raise ValueError(
                    f"{robot.name} has two arms: write robot_ip_left and robot_ip_right"
                )
            names, given = (
                ("robot_ip_left", "robot_ip_right"),
                (self.robot_ip_left, self.robot_ip_right),
            )
        hosts = []
        for name, host in zip(names, given, strict=True):
            if host is None and self.driver == "sdk":
                raise ValueError(f"driver 'sdk' needs {name}: write your arm's address")
            hosts.append(LOOPBACK if host is None else str(host))
        return tuple(hosts)

    def camera_configs_for(self, robot: Robot) -> dict[str, CameraConfig]:
        """The LeRobot camera config of every camera, by name.

        Args:
            robot: The robot record (its hand cameras name the twin's wrist views).

        Returns:
            ``camera_configs`` if given; else per ``camera_ids`` name a RealSense with depth
            (``sdk``) or a twin camera (``sim``); with neither, the twin's front view and every
            hand camera of the record (``sim``) or no camera (``sdk``).
        """
        if self.camera_configs is not None:
            return dict(self.camera_configs)
        width, height = self.image_size  # type: ignore[misc]
        if self.driver == "sdk":
            from lerobot.cameras.realsense import RealSenseCameraConfig

            return {
                name: RealSenseCameraConfig(
                    serial_number_or_name=str(serial),
                    fps=self.camera_fps,
                    width=width,
                    height=height,
                    use_depth=True,
                )
                for name, serial in (self.camera_ids or {}).items()
            }
        from rmb_lerobot.envs.real.cameras import TwinCameraConfig

        names = list(self.camera_ids) if self.camera_ids else ["front", *robot.cameras]
        configs: dict[str, CameraConfig] = {}
        for name in names:
            hand = "hand" in name
            arm = next(
                (
                    i
                    for i, a in enumerate(robot.arms)
                    if a.hand_camera is not None and a.hand_camera.name == name
                ),
                1 if name.startswith("right") and len(robot.arms) > 1 else 0,
            )
            configs[name] = TwinCameraConfig(
                view="hand" if hand else "front",
                arm=arm,
                fps=self.camera_fps,
                width=width,
                height=height,
                use_depth=True,
            )
        return configs
