"""Configs of the LeRobot teleoperators ``rmb_gello`` and ``rmb_spacemouse``.

Importing this module registers both types (``--teleop.type=rmb_gello``);
:mod:`rmb_lerobot.registration` imports it when LeRobot imports ``lerobot_env_rmb``. LeRobot
finds a device class by the config class's name minus ``Config``, and for a config module
named ``config_<x>`` it looks in the sibling module ``<x>``
(``lerobot.utils.import_utils.make_device_from_device_class``): the classes live in
:mod:`.teleop_devices`. Nothing here imports a device SDK.

Both drive ``rmb_ur5e``, ``rmb_xarm7`` or both arms of ``rmb_ur5e_dual`` (one device per arm:
two SpaceMice, or a GELLO pair as RMB's ``Gello_RealUR5eDual.yaml`` describes; the keys of
arm 0 get the prefix ``left_``, those of arm 1 ``right_``, as the dual robot's):

- ``rmb_gello`` emits the robot's joint keys (``<joint>.pos``, ``gripper.pos``), so it fits
  the stock ``lerobot-teleoperate`` / ``lerobot-record`` with the robot's default joint
  action space.
- ``rmb_spacemouse`` emits an end-effector twist (``ee_x.vel`` .. ``ee_yaw.vel``) and the
  absolute ``gripper.pos``: run the robot with ``--robot.action_space=ee_velocity``, which
  keeps the end-effector target, solves IK and sends joints through the safety layer (a
  teleoperator sees no robot state in LeRobot's loops).

What the stock loops do not let a teleoperator see, it cannot check: ``--fps`` (the loop's
rate) and ``--robot.command_duration_s`` are not passed to it. So the period between its
``get_action`` calls is measured and a warning names the flags when it is far from the
period the teleoperator assumes (:class:`~.teleop_base.RateCheck`).
"""

from __future__ import annotations

from dataclasses import dataclass

from lerobot.teleoperators.config import TeleoperatorConfig

from rmb_lerobot.envs.real.lerobot_devices.config import DEFAULT_COMMAND_DURATION_S

GELLO_TELEOP_TYPE = "rmb_gello"
SPACEMOUSE_TELEOP_TYPE = "rmb_spacemouse"
SINGLE_ARM_ROBOTS = ("rmb_ur5e", "rmb_xarm7")
DUAL_ARM_ROBOT = "rmb_ur5e_dual"
DEVICE_ROBOTS = (*SINGLE_ARM_ROBOTS, DUAL_ARM_ROBOT)


def num_arms(robot: str) -> int:
    """Arms of a robot type (each driven by its own device)."""
    return 2 if robot == DUAL_ARM_ROBOT else 1


def _check_robot(teleop: str, robot: str) -> None:
    if robot not in DEVICE_ROBOTS:
        raise ValueError(f"{teleop}: robot must be one of {DEVICE_ROBOTS}, got {robot!r}")


@TeleoperatorConfig.register_subclass(GELLO_TELEOP_TYPE)
@dataclass(kw_only=True)
class RmbGelloConfig(TeleoperatorConfig):
    """A GELLO leader arm on a serial port (dynamixel-sdk, extra ``gello``).

    ``--teleop.type=rmb_gello --teleop.port=/dev/ttyUSB0 --teleop.joint_offsets=[...]``,
    or ``--teleop.rmb_config=Gello_RealUR5e.yaml`` to take port and calibration from an RMB
    GELLO config (its arm 0; for ``rmb_ur5e_dual`` its arms 0 and 1, left and right: the
    dual robot needs ``rmb_config``).

    The stock loops show the teleoperator no robot state, so the handover uses
    ``start_joints``, where the robot stands when the session starts (default: the robot
    record's home, where the twins start): the offsets are aligned to it (by multiples of
    2π), the robot is held there until every GELLO joint is within ``ready_tolerance_deg``
    of it, then the command blends into the GELLO pose over ``blend_steps`` steps (RMB's
    readiness and blend).

    Attributes:
        robot: The robot type driven: ``rmb_ur5e``, ``rmb_xarm7`` or ``rmb_ur5e_dual``.
        port: The GELLO's serial adapter.
        joint_ids: Servo ID per arm joint (default 1..n).
        joint_offsets: Per joint, the servo angle (rad) at the robot's zero (GELLO's
            calibration); required unless ``rmb_config`` is given.
        joint_signs: Per joint +1 or -1 (default all +1).
        gripper: ``[servo ID, open deg, closed deg]``; None: the gripper stays open.
        rmb_config: An RMB ``Gello_*.yaml``; its arm 0 (two arms: 0 and 1) replaces port
            and calibration.
        start_joints: The robot's arm joints at the start (rad; dual: left's, then
            right's); default the record's home.
        ready_tolerance_deg: Readiness: every joint this close to ``start_joints``.
        blend_steps: Steps of the linear blend into the GELLO pose.
        baudrate: The servo bus's baud rate.
    """

    robot: str = "rmb_ur5e"
    port: str | None = None
    joint_ids: list[int] | None = None
    joint_offsets: list[float] | None = None
    joint_signs: list[int] | None = None
    gripper: list[float] | None = None
    rmb_config: str | None = None
    start_joints: list[float] | None = None
    ready_tolerance_deg: float = 30.0
    blend_steps: int = 50
    baudrate: int = 57600

    def __post_init__(self) -> None:
        _check_robot(GELLO_TELEOP_TYPE, self.robot)
        if self.rmb_config is None and num_arms(self.robot) > 1:
            raise ValueError(
                f"rmb_gello: {self.robot} has two arms: give RMB's two-arm GELLO config "
                "(--teleop.rmb_config=Gello_RealUR5eDual.yaml: port and calibration per arm)"
            )
        if self.rmb_config is None:
            if not self.port:
                raise ValueError(
                    "rmb_gello: give the GELLO's serial port (--teleop.port=/dev/ttyUSB0) or an "
                    "RMB GELLO config (--teleop.rmb_config=Gello_RealUR5e.yaml)"
                )
            if self.joint_offsets is None:
                raise ValueError(
                    "rmb_gello: give joint_offsets (rad, GELLO's calibration, as in RMB's "
                    "Gello_*.yaml) or rmb_config; there is no default for a hand-built arm"
                )
        if self.gripper is not None and len(self.gripper) != 3:
            raise ValueError(
                f"rmb_gello: gripper is [servo ID, open deg, closed deg], got {self.gripper}"
            )


@TeleoperatorConfig.register_subclass(SPACEMOUSE_TELEOP_TYPE)
@dataclass(kw_only=True)
class RmbSpacemouseConfig(TeleoperatorConfig):
    """A 3Dconnexion SpaceMouse (pyspacemouse 2.x, extra ``spacemouse``, system hidapi).

    ``--robot.action_space=ee_velocity --teleop.type=rmb_spacemouse``. Each step's RMB
    delta (1 cm, 5 mrad per step at full deflection) is sent as a velocity held for
    ``command_duration_s``, so the robot's end-effector target moves by exactly RMB's delta
    per action: keep it equal to the robot's ``command_duration_s`` (``1 / fps``); a warning
    says so when the loop's measured period differs.

    ``rmb_ur5e_dual`` (``--robot.left_arm_config.action_space=ee_velocity``, the right arm's
    too) takes one SpaceMouse per arm: ``--teleop.paths=[/dev/hidrawL,/dev/hidrawR]`` or RMB's
    ``SpaceMouseDual.yaml`` (``--teleop.rmb_config``).

    The gripper command is absolute (``gripper.pos``) and starts at ``gripper_start``, not
    at the measured gripper: LeRobot's ``lerobot-record`` / ``lerobot-teleoperate`` call
    ``send_feedback(observation)`` only for the Unitree G1, so a teleoperator never sees the
    robot's state. With the twins and after ``lerobot-record``'s reset the gripper is open
    (the record's home, the default); set ``gripper_start`` when it is not.

    Attributes:
        robot: The robot type driven: ``rmb_ur5e``, ``rmb_xarm7`` or ``rmb_ur5e_dual``.
        path: The device's ``/dev/hidrawN``; None: the first SpaceMouse found (one arm).
        paths: One ``/dev/hidrawN`` per arm (left, then right); replaces ``path``.
        rmb_config: RMB's SpaceMouse YAML (``SpaceMouseDual.yaml``: a ``device_params.path``
            per arm index); replaces ``path`` / ``paths``.
        pos_scale: Metres per step at full deflection.
        rpy_scale: Radians per step at full deflection (yaw twice this).
        gripper_scale: Gripper command units per step while a button is held (first
            button closes, last button opens).
        reads_per_step: Device reads per step (the last is used).
        command_duration_s: The robot's command duration (s): velocity = delta / this.
        gripper_start: The gripper command (per arm) the first action sends; None: the
            record's home (open).
    """

    robot: str = "rmb_ur5e"
    path: str | None = None
    pos_scale: float = 1e-2
    rpy_scale: float = 5e-3
    gripper_scale: float = 5.0
    reads_per_step: int = 10
    command_duration_s: float = DEFAULT_COMMAND_DURATION_S
    paths: list[str] | None = None
    rmb_config: str | None = None
    gripper_start: float | None = None

    def __post_init__(self) -> None:
        _check_robot(SPACEMOUSE_TELEOP_TYPE, self.robot)
        arms = num_arms(self.robot)
        if self.paths is not None and len(self.paths) != arms:
            raise ValueError(
                f"rmb_spacemouse: {self.robot} has {arms} arm(s), one SpaceMouse each; got "
                f"{len(self.paths)} paths {self.paths}"
            )
        if arms > 1 and self.paths is None and self.rmb_config is None:
            raise ValueError(
                f"rmb_spacemouse: {self.robot} has two arms, one SpaceMouse each: give "
                "--teleop.paths=[/dev/hidrawL,/dev/hidrawR] or RMB's SpaceMouseDual.yaml "
                "(--teleop.rmb_config)"
            )
        if not self.command_duration_s > 0:
            raise ValueError(
                f"rmb_spacemouse: command_duration_s must be > 0, got {self.command_duration_s}"
            )
