"""Configs of the LeRobot device types this package adds: robots ``rmb_ur5e``, ``rmb_xarm7``,
``rmb_ur5e_dual`` and the teleoperators ``rmb_scripted`` and ``rmb_keyboard``.

Importing this module registers the five types with LeRobot (``--robot.type=rmb_ur5e``,
``--teleop.type=rmb_scripted``); :mod:`rmb_lerobot.registration` imports it when LeRobot
imports ``lerobot_env_rmb``. LeRobot finds each device class by the config class's name minus
``Config`` in the config module's *parent* package (``lerobot.utils.import_utils.
make_device_from_device_class``), which is why :mod:`rmb_lerobot.envs.real.lerobot_devices`
exports the device classes from its ``__init__``.

Nothing here imports a driver, a twin or MuJoCo: only the device classes do, when built.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from lerobot.cameras import CameraConfig
from lerobot.robots.config import RobotConfig
from lerobot.teleoperators.config import TeleoperatorConfig

from rmb_lerobot.envs.real.cameras.config_twin import TWIN_CAMERA_TYPE
from rmb_lerobot.envs.real.drivers.common import DRIVER_KINDS, check_driver_config
from rmb_lerobot.envs.real.limits import WATCHDOG_TIMEOUT

SIM_HOST = "127.0.0.1"
"""The address ``driver: sim`` uses when none is given (the twin runs in this process)."""

DEFAULT_COMMAND_DURATION_S = 1.0 / 30.0
"""Duration given to the arm per command: one period of LeRobot's default 30 fps."""

ROBOT_TYPES = {"rmb_ur5e": "ur5e", "rmb_xarm7": "xarm7", "rmb_ur5e_dual": "ur5e_dual"}
"""LeRobot robot type -> the robot record it drives (:mod:`rmb_lerobot.envs.robots`)."""

JOINT_ACTIONS = "joint"
EE_VELOCITY_ACTIONS = "ee_velocity"
ACTION_SPACES = (JOINT_ACTIONS, EE_VELOCITY_ACTIONS)
"""Values of a robot's ``action_space`` (:class:`RmbArmConfig`)."""

SCRIPTED_TELEOP_TYPE = "rmb_scripted"
SCRIPTED_MOTIONS = ("wave", "hold")
KEYBOARD_TELEOP_TYPE = "rmb_keyboard"
KEYBOARD_KEY_SOURCES = ("auto", "terminal", "pynput")


@dataclass
class RmbArmConfig:
    """How to reach one real arm, and how the LeRobot plugin commands it.

    Attributes:
        driver: ``"sim"`` drives the arm's MuJoCo twin in this process (dry runs, tests);
            ``"sdk"`` drives the arm at ``host`` with its vendor SDK (extras ``ur5e`` /
            ``xarm7``).
        host: The arm controller's address. Required with ``sdk`` (there is no default lab
            address); ``sim`` uses 127.0.0.1 when it is left out and refuses any other
            non-loopback address.
        cameras: LeRobot camera configs by name (``intelrealsense``, ``opencv``, or
            ``rmb_twin`` for the twin's rendered cameras), each with width, height and fps.
            A camera streaming depth (``use_depth``) adds a ``<name>_depth`` observation.
        command_duration_s: Duration (s) given to the arm with every action: the time it has
            to reach the target, which also bounds how far one action may move it (the safety
            layer's per-step clamp is ``2 * v_lim * duration``). Set it to ``1 / fps`` of the
            loop that sends the actions (LeRobot's default fps is 30).
        watchdog_timeout_s: The arm is stopped when no action arrives within this long after
            the previous action's duration ran out (the safety layer's watchdog); the next
            action then resumes streaming from where the arm stands.
        action_space: ``"joint"``: an action is the joint targets and the gripper command
            (``<joint>.pos``, ``gripper.pos``). ``"ee_velocity"``: an action is an
            end-effector twist in the arm's base frame (``ee_x.vel`` .. ``ee_yaw.vel``, m/s
            and rad/s, held for ``command_duration_s``) and ``gripper.pos``; the robot keeps
            its own end-effector target, started at the measured pose, solves it by IK and
            sends the joints through the safety layer (:mod:`.ee_action`). This is what a
            Cartesian teleoperator (``rmb_keyboard``) drives through the stock LeRobot loops.
        ramp_first_action: With joint actions, the first action of a stream (after
            ``connect``, or after the watchdog stopped the arm) that lies further from the
            measured joints than a reset move covers in one command duration is reached by the
            safety layer's duration-scaled reset move (RMB's reset speed) before it is sent,
            instead of being clamped into a full-speed lunge or refused as a jump. This lets a
            teleoperator or a replayed episode start anywhere. ``False``: send it as it is.
    """

    driver: str = "sim"
    host: str | None = None
    cameras: dict[str, CameraConfig] = field(default_factory=dict)
    command_duration_s: float = DEFAULT_COMMAND_DURATION_S
    watchdog_timeout_s: float = WATCHDOG_TIMEOUT
    action_space: str = JOINT_ACTIONS
    ramp_first_action: bool = True

    def resolved_host(self, arm: str) -> str:
        """The address to use: ``host``, or 127.0.0.1 for ``sim`` when none is given.

        Args:
            arm: The arm's name for messages.

        Returns:
            The checked address.

        Raises:
            ValueError: Unknown driver, ``sdk`` without a host, ``sim`` with a non-loopback
                host, a duration / timeout that is not positive, or an unknown action space.
        """
        if self.action_space not in ACTION_SPACES:
            raise ValueError(
                f"{arm}: action_space must be one of {ACTION_SPACES}, got {self.action_space!r}"
            )
        if self.driver not in DRIVER_KINDS:
            raise ValueError(f"{arm}: driver must be one of {DRIVER_KINDS}, got {self.driver!r}")
        if self.host is None and self.driver == "sdk":
            raise ValueError(
                f"{arm}: driver 'sdk' needs the arm's address: pass host=<controller IP> "
                "(e.g. --robot.host=...); there is no default lab address"
            )
        host = SIM_HOST if self.host is None else self.host
        check_driver_config(arm, self.driver, host)
        check_twin_cameras(arm, self.driver, self.cameras)
        for name in ("command_duration_s", "watchdog_timeout_s"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{arm}: {name} must be > 0, got {getattr(self, name)}")
        return host


def check_twin_cameras(arm: str, driver: str, cameras: dict[str, CameraConfig]) -> None:
    """Refuse twin cameras (``type: rmb_twin``) on an arm that is not its twin.

    Args:
        arm: The arm's name for messages.
        driver: The arm's driver.
        cameras: The cameras that arm opens.

    Raises:
        ValueError: A twin camera with ``driver: sdk``.
    """
    twins = [name for name, c in cameras.items() if c.type == TWIN_CAMERA_TYPE]
    if twins and driver != "sim":
        raise ValueError(
            f"{arm}: cameras {twins} render the MuJoCo twin (type {TWIN_CAMERA_TYPE}) and need "
            "driver 'sim'; give the real cameras (intelrealsense, opencv) with driver 'sdk'"
        )


@RobotConfig.register_subclass("rmb_ur5e")
@dataclass(kw_only=True)
class RmbUR5eConfig(RobotConfig, RmbArmConfig):
    """A UR5e with a Robotiq 2F-85 (ur-rtde + the URCap socket, or its twin).

    ``--robot.type=rmb_ur5e --robot.driver=sdk --robot.host=<IP>``; see
    :class:`RmbArmConfig` for the fields.
    """

    def __post_init__(self) -> None:
        super().__post_init__()
        self.resolved_host("rmb_ur5e")


@RobotConfig.register_subclass("rmb_xarm7")
@dataclass(kw_only=True)
class RmbXarm7Config(RobotConfig, RmbArmConfig):
    """An xArm7 with its gripper (xarm-python-sdk, or its twin).

    ``--robot.type=rmb_xarm7 --robot.driver=sdk --robot.host=<IP>``; see
    :class:`RmbArmConfig` for the fields.
    """

    def __post_init__(self) -> None:
        super().__post_init__()
        self.resolved_host("rmb_xarm7")


@RobotConfig.register_subclass("rmb_ur5e_dual")
@dataclass(kw_only=True)
class RmbUR5eDualConfig(RobotConfig):
    """Two UR5e arms, composed as LeRobot's bimanual robots are (``bi_so_follower``).

    Every key of an arm is prefixed ``left_`` / ``right_``, its cameras too. Cameras not
    attached to an arm go in ``cameras`` and keep their names (the left arm opens them).

    Attributes:
        left_arm_config: The left arm (``--robot.left_arm_config.host=<IP>``).
        right_arm_config: The right arm.
        cameras: Cameras of the cell, not prefixed.
    """

    left_arm_config: RmbArmConfig = field(default_factory=RmbArmConfig)
    right_arm_config: RmbArmConfig = field(default_factory=RmbArmConfig)
    cameras: dict[str, CameraConfig] = field(default_factory=dict)

    def __post_init__(self) -> None:
        super().__post_init__()
        for side, arm in (("left", self.left_arm_config), ("right", self.right_arm_config)):
            arm.resolved_host(f"rmb_ur5e_dual {side} arm")
            for config in arm.cameras.values():
                for attr in ("width", "height", "fps"):
                    if getattr(config, attr) is None:
                        raise ValueError(f"{side} arm camera needs {attr} to be used in a robot")
        check_twin_cameras("rmb_ur5e_dual", self.left_arm_config.driver, self.cameras)
        clash = set(self.cameras) & {
            f"{side}_{name}"
            for side, arm in (("left", self.left_arm_config), ("right", self.right_arm_config))
            for name in arm.cameras
        }
        if clash:
            raise ValueError(f"cell camera names clash with prefixed arm cameras: {sorted(clash)}")


@TeleoperatorConfig.register_subclass(SCRIPTED_TELEOP_TYPE)
@dataclass(kw_only=True)
class RmbScriptedConfig(TeleoperatorConfig):
    """A scripted command stream for tests and dry runs: no device, no operator.

    It emits every joint action key of the robot type named in ``robot``, around the home
    pose of its robot record (where the twins start). It sees no robot state: the robot's
    ``ramp_first_action`` (on by default) moves an arm that stands elsewhere to the first
    action at reset speed before the stream starts.

    Attributes:
        robot: The robot type it drives: ``rmb_ur5e``, ``rmb_xarm7`` or ``rmb_ur5e_dual``.
        motion: ``"wave"``: every arm joint swings ``amplitude_deg`` about home with period
            ``period_s`` (alternate joints in opposite phase) and the gripper closes halfway
            and opens once a period; ``"hold"``: home, gripper open.
        amplitude_deg: Joint amplitude of the wave (degrees).
        period_s: Period of the wave (s).
        home: The joint vector to move about, in action-key order (per arm: joints, then the
            gripper command); default the record's home (the twins' start pose).
    """

    robot: str = "rmb_ur5e"
    motion: str = "wave"
    amplitude_deg: float = 5.0
    period_s: float = 4.0
    home: list[float] | None = None

    def __post_init__(self) -> None:
        if self.robot not in ROBOT_TYPES:
            raise ValueError(f"rmb_scripted: robot must be one of {sorted(ROBOT_TYPES)}")
        if self.motion not in SCRIPTED_MOTIONS:
            raise ValueError(f"rmb_scripted: motion must be one of {SCRIPTED_MOTIONS}")
        if not self.period_s > 0 or not 0 <= self.amplitude_deg <= 45:
            raise ValueError("rmb_scripted: needs period_s > 0 and 0 <= amplitude_deg <= 45")


@TeleoperatorConfig.register_subclass(KEYBOARD_TELEOP_TYPE)
@dataclass(kw_only=True)
class RmbKeyboardConfig(TeleoperatorConfig):
    """RMB's keyboard bindings as end-effector velocity actions, with or without a display.

    Drives a robot with ``--robot.action_space=ee_velocity``: each step it emits the twist
    keys (``ee_x.vel`` .. ``ee_yaw.vel``) and ``gripper.pos`` of every arm. One key press moves
    the target by RMB's step (1 cm, 0.05 rad; yaw 0.1 rad; gripper 50 of 255) when the loop
    runs at ``fps`` and the robot's ``command_duration_s`` is ``1 / fps``.

    Attributes:
        robot: The robot type it drives: ``rmb_ur5e``, ``rmb_xarm7`` or ``rmb_ur5e_dual``
            (Tab / 1 / 2 switch the arm the keys move).
        fps: The loop's rate (LeRobot's ``--fps``): a press of one step becomes a velocity of
            step * fps for that step.
        keys: ``"terminal"``: the terminal on standard input in cbreak mode (no display; over
            SSH too); ``"pynput"``: the desktop session; ``"auto"``: the terminal when
            standard input is one, else pynput where a display exists.
        gripper_start: The gripper command it starts from (0 = open): it sees no robot
            state, so the first action sets the gripper to this.
    """

    robot: str = "rmb_ur5e"
    fps: float = 30.0
    keys: str = "auto"
    gripper_start: float = 0.0

    def __post_init__(self) -> None:
        if self.robot not in ROBOT_TYPES:
            raise ValueError(f"rmb_keyboard: robot must be one of {sorted(ROBOT_TYPES)}")
        if self.keys not in KEYBOARD_KEY_SOURCES:
            raise ValueError(
                f"rmb_keyboard: keys must be one of {KEYBOARD_KEY_SOURCES}, got {self.keys!r}"
            )
        if not self.fps > 0:
            raise ValueError(f"rmb_keyboard: fps must be > 0, got {self.fps}")
