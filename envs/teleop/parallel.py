"""Parallel collection: one operator's commands sent to N sim envs, one episode per env.

RMB's paper shows one operator driving many simulated envs at once, each with its objects
elsewhere, so one demonstration yields N episodes. Here each env is a :class:`Lane`: the env,
the episode being recorded in it and whether its task succeeded. The device drives env 0's
end-effector target (IK solved once, on env 0); the resulting **joint** command goes to every
lane. The robot is the same in every lane (only the objects move with the world or the random
shift), so the same joint command puts every end effector at the same pose; sending joints
rather than the eef pose costs one IK per step instead of N, and keeps every lane's recorded
command identical to what the operator saw in env 0 (an eef command solved per lane could land
on a different IK branch). With ``--save-success-only`` each lane's episode is kept only if
that lane's task succeeded.

Lane ``k`` of demonstration ``d`` is reset into world ``worlds[(d * N + k) % len(worlds)]``
(``--world-idx``), else into world ``(d * N + k) % num_worlds`` when N > 1 (so the lanes
differ), else the seed draws it (one env, as before); a replay puts lane ``k`` in the log's
world plus ``k``. Its seed is ``seed + reset * N + k``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rmb_lerobot import keys as K
from rmb_lerobot.envs.base import RmbEnv
from rmb_lerobot.episode import EpisodeWriter


@dataclass
class Lane:
    """One env of a session and the episode being recorded in it.

    Attributes:
        env: The env.
        index: Its position among the session's envs (0 is the one the device sees).
        writer: The episode being recorded (None outside recording).
        success: Whether the task has succeeded since the last reset.
        obs: The last observation (for the live view).
    """

    env: RmbEnv
    index: int = 0
    writer: EpisodeWriter | None = None
    success: bool = False
    obs: dict[str, Any] = field(default_factory=dict)

    def record_and_step(self, command: np.ndarray, recording: bool) -> None:
        """Record the step (state before the command, as RMB does) if ``recording``, then
        send ``command``."""
        if recording and self.writer is not None:
            self.writer.append(self.env.rmb_step_data(command))
        self.obs, _, _, _, info = self.env.step(command)
        self.success = bool(info.get("is_success", False))

    def open(
        self,
        path: Path,
        task_desc: str | None,
        depth_codec: str,
        *,
        background_encoding: bool = True,
    ) -> None:
        """Start an episode at ``path`` (built in a hidden temporary until :meth:`finish`).

        Args:
            path: The episode's destination.
            task_desc: Its ``task_desc`` (None: the task's own).
            depth_codec: Depth video codec of the compact format.
            background_encoding: Encode images on the writer's background thread.
        """
        self.abort()
        attrs = {**self.env.rmb_attrs(), K.ATTR_DEMO_NAME: path.stem}
        if task_desc:
            attrs[K.ATTR_TASK_DESC] = task_desc
        self.writer = EpisodeWriter(
            path, attrs, depth_codec=depth_codec, background_encoding=background_encoding
        )

    def finish(self, save: bool, success_only: bool) -> tuple[Path | None, str]:
        """Move the episode into place (``save``, and a success if ``success_only``) or drop it.

        Returns:
            The saved path (None if nothing was saved) and what happened, for the log (empty
            when no episode was being recorded).
        """
        writer, self.writer = self.writer, None
        if writer is None:
            return None, ""
        if len(writer) == 0:
            writer.abort()
            return None, "nothing recorded: no episode written"
        if save and success_only and not self.success:
            writer.abort()
            return None, "the task did not succeed and --save-success-only is set: discarded"
        if not save:
            writer.abort()
            return None, "episode discarded"
        path = writer.close()
        return path, f"saved {path} ({len(writer)} steps)"

    def abort(self) -> bool:
        """Drop the episode being recorded, if any; returns whether there was one."""
        writer, self.writer = self.writer, None
        if writer is None:
            return False
        writer.abort()
        return True


def lane_world(
    worlds: tuple[int, ...] | None, num_worlds: int, demo: int, lane: int, num_lanes: int
) -> int | None:
    """The world lane ``lane`` of demonstration ``demo`` is reset into (None: the seed draws it).

    Args:
        worlds: ``--world-idx`` (None or empty: not given).
        num_worlds: The task's number of worlds.
        demo: Demonstrations kept so far.
        lane: The lane's index.
        num_lanes: The number of lanes (envs).
    """
    slot = demo * num_lanes + lane
    if worlds:
        return worlds[slot % len(worlds)]
    if num_lanes > 1:
        return slot % num_worlds
    return None


def lane_seed(seed: int, reset: int, lane: int, num_lanes: int) -> int:
    """The seed of lane ``lane``'s reset number ``reset``: distinct across lanes and resets."""
    return seed + reset * num_lanes + lane
