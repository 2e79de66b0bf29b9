"""Replay: a recorded RMB episode's command, re-commanded step by step (RMB's ``--replay_log``).

RMB replays the env's command keys (``command_joint_pos`` for its arms: joint targets and the
gripper per arm); a ``_rel`` key is integrated from the log's first absolute value (RMB's
``TeleopBase`` 132-162). The world comes from the log's ``world_idx`` attribute, so the replay
starts where the recording did.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rmb_lerobot import keys as K
from rmb_lerobot.envs.robots import Robot
from rmb_lerobot.envs.teleop.command import gripper_closure
from rmb_lerobot.envs.teleop.device import DeviceReading, InputDevice, JointTarget
from rmb_lerobot.episode import open_episode
from rmb_lerobot.errors import RmbFormatError

REPLAY_KEYS = (
    K.COMMAND_JOINT_POS,
    K.COMMAND_JOINT_POS_REL,
    K.MEASURED_JOINT_POS,
    K.MEASURED_JOINT_POS_REL,
)
"""Keys a log can be replayed from (joint vectors: per arm its joints, then its gripper)."""


class ReplayDevice(InputDevice):
    """Joint targets read from an RMB episode, one row per :meth:`read`.

    Args:
        path: The episode (``.rmb`` directory or ``.hdf5`` file).
        robot: The robot being driven (its joint layout must match the log's).
        key: Which key to replay (one of :data:`REPLAY_KEYS`; RMB's default, the env's command).

    Attributes:
        world_idx: The log's world (reset the env into it before replaying).
        env_attr: The log's ``env`` attribute (e.g. ``MujocoUR5eCableEnv``).
    """

    name = "replay"

    def __init__(self, path: str | Path, robot: Robot, key: str = K.COMMAND_JOINT_POS):
        if key not in REPLAY_KEYS:
            raise ValueError(
                f"cannot replay key {key!r}; replayable keys: {', '.join(REPLAY_KEYS)}"
            )
        self.path = Path(path)
        self.robot = robot
        self.key = key
        self.world_idx = 0
        self.env_attr = ""
        self.task_desc = ""
        self.commands = np.zeros((0, robot.layout.num_joints))
        self.step = 0

    def connect(self) -> None:
        """Read the log's key into memory.

        Raises:
            RmbFormatError: The log is not an RMB episode, lacks the key, or its joint vector
                does not fit the robot.
        """
        with open_episode(self.path) as episode:
            absolute = K.abs_key(self.key)
            for needed in dict.fromkeys((self.key, absolute)):
                if needed not in episode:
                    raise RmbFormatError(
                        f"the replay log has no {needed!r} (it has {', '.join(episode.keys())})",
                        path=self.path,
                        key=needed,
                    )
            values = np.asarray(episode[self.key][:], dtype=np.float64)
            if self.key != absolute:  # integrate from the first absolute value (RMB's rule)
                values = np.asarray(episode[absolute][0], dtype=np.float64) + np.cumsum(values, 0)
            self.world_idx = int(episode.attrs.get(K.ATTR_WORLD_IDX, 0))
            self.env_attr = str(episode.attrs.get(K.ATTR_ENV, ""))
            self.task_desc = str(episode.attrs.get(K.ATTR_TASK_DESC, ""))
        expected = self.robot.layout.num_joints
        if values.ndim != 2 or values.shape[1] != expected or len(values) == 0:
            raise RmbFormatError(
                f"{self.key} has shape {values.shape}; {self.robot.name} needs (T, {expected}) "
                "with T >= 1 (a log of another robot?)",
                path=self.path,
                key=self.key,
            )
        self.commands = values
        self.restart()

    def restart(self) -> None:
        """Go back to the log's first step."""
        self.step = 0

    @property
    def done(self) -> bool:
        """Whether every step of the log has been read."""
        return self.step >= len(self.commands)

    def __len__(self) -> int:
        return len(self.commands)

    def read(self) -> DeviceReading:
        """The next step's joint targets (no command once the log is done: the robot holds)."""
        if self.done:
            return DeviceReading()
        row = self.commands[self.step]
        self.step += 1
        arms = {}
        for i, ((joints, grip), arm) in enumerate(
            zip(self.robot.joint_slices(), self.robot.arms, strict=True)
        ):
            closure = gripper_closure(row[grip], arm.gripper.open, arm.gripper.closed)
            arms[i] = JointTarget(joints=row[joints].copy(), gripper=closure)
        return DeviceReading(arms=arms)

    def close(self) -> None:
        """Nothing to release (the log was read in :meth:`connect`)."""
