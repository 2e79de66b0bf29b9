"""The teleoperation loop (RMB's ``TeleopBase.run``): keys, device, env, recorder, pacing.

Once per control step the loop polls its key source, lets the phase machine
(:mod:`~rmb_lerobot.envs.teleop.phases`) take the keys of the current phase, feeds the rest
to a keyboard device, reads the device in the driving phases (others hold the last command),
records the step *before* sending it (as RMB does, so each row pairs the state with the command
sent from it), steps the env and sleeps to the env's control period.

Episodes are written with :class:`~rmb_lerobot.episode.EpisodeWriter`, which builds each one in
a hidden temporary and moves it into place only when it is saved: a discarded episode, Esc,
Ctrl-C or an exception leaves nothing at the destination. Signals handled by
:mod:`~rmb_lerobot.envs.interrupts` are raised between two steps.
"""

from __future__ import annotations

import logging
import re
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol, runtime_checkable

import numpy as np

from rmb_lerobot import keys as K
from rmb_lerobot.envs.base import RmbEnv
from rmb_lerobot.envs.interrupts import raise_if_signalled, recording
from rmb_lerobot.envs.teleop.command import CommandTracker
from rmb_lerobot.envs.teleop.device import InputDevice, KeySource
from rmb_lerobot.envs.teleop.phases import PROMPTS, Phase, PhaseMachine, Transition
from rmb_lerobot.episode import EpisodeFormat, EpisodeWriter

logger = logging.getLogger(__name__)


@runtime_checkable
class KeyDriven(Protocol):
    """A device driven by key presses routed to it by the loop (the keyboard)."""

    def feed(self, keys: list[str]) -> None:
        """Queue key presses for the next read."""
        ...


@dataclass(frozen=True)
class TeleopConfig:
    """What a session records and how.

    Attributes:
        out: Directory of the episodes (created if missing).
        fmt: ``"rmb"`` (``NAME.rmb``, compact) or ``"hdf5"`` (``NAME.hdf5``).
        demo_name: File name prefix (default: the env's RMB name, e.g. ``MujocoUR5eCable``).
        world_idx: Worlds the episodes cycle through; None: drawn from the seed.
        task_desc: The episodes' ``task_desc`` (default: the task's own description).
        save_success_only: ``s`` keeps only an episode whose task succeeded.
        sync_before_record: Pass through the unrecorded SYNC phase before recording.
        seed: Reset number k uses seed + k.
        realtime: Pace the loop to the env's control period (off: as fast as it runs).
        max_episodes: Quit after this many saved episodes (None: until Esc).
        replay: Run the replay phases (the device is a replayed log).
        auto_replay: Replay without waiting for ``n``.
        save_replay: Record each replay as an episode.
        replay_repeat: Replays before quitting.
        depth_codec: Depth video codec of the compact format.
    """

    out: Path
    fmt: str = "rmb"
    demo_name: str | None = None
    world_idx: tuple[int, ...] | None = None
    task_desc: str | None = None
    save_success_only: bool = False
    sync_before_record: bool = False
    seed: int = 0
    realtime: bool = True
    max_episodes: int | None = None
    replay: bool = False
    auto_replay: bool = False
    save_replay: bool = False
    replay_repeat: int = 1
    depth_codec: str = "rmb-videoio"


@dataclass
class TeleopResult:
    """What a session did."""

    saved: list[Path] = field(default_factory=list)
    discarded: int = 0  # episodes recorded and not kept (f, failure with success-only, Esc)
    steps: int = 0  # control steps run


class TeleopSession:
    """One operator, one device, one env: RMB's teleoperation phases until Esc.

    Args:
        env: The env (not a ``TimeLimit`` wrapper: teleoperation has no step limit).
        device: The connected input device.
        keys: Where phase keys (and a keyboard device's motion keys) come from.
        config: What to record.
        log: Where prompts go (default: the module logger at INFO).
        clock: Monotonic seconds (tests pass a fake).
        sleep: Sleeps seconds (tests pass a fake).
    """

    def __init__(
        self,
        env: RmbEnv,
        device: InputDevice,
        keys: KeySource,
        config: TeleopConfig,
        *,
        log: Callable[[str], None] | None = None,
        clock: Callable[[], float] = time.monotonic,
        sleep: Callable[[float], None] = time.sleep,
    ):
        self.env = env
        self.device = device
        self.keys = keys
        self.config = config
        self.log = log or logger.info
        self.clock = clock
        self.sleep = sleep
        self.machine = PhaseMachine(
            sync_before_record=config.sync_before_record,
            replay=config.replay,
            auto=config.auto_replay,
        )
        self.tracker: CommandTracker | None = None
        self.writer: EpisodeWriter | None = None
        self.result = TeleopResult()
        self.success = False
        self._resets = 0
        self._replays = 0
        self._deadline = 0.0

    @property
    def phase(self) -> Phase:
        return self.machine.phase

    # ------------------------------------------------------------------ loop
    def run(self) -> TeleopResult:
        """Run until Esc (or ``max_episodes`` saved, or the replays done); returns what was
        saved. An exception (Ctrl-C included) discards the episode being recorded and
        propagates."""
        self.config.out.mkdir(parents=True, exist_ok=True)
        try:
            with recording():
                self._reset()
                self.log(PROMPTS[self.phase])
                self._deadline = self.clock()
                while self.phase is not Phase.QUIT:
                    self.step()
        finally:
            self._discard()
        return self.result

    def step(self) -> None:
        """One control step: keys, phase, device, record, env step, pacing."""
        raise_if_signalled()
        pressed = self.keys.poll()
        phase_keys = self.machine.keys
        transition = self.machine.advance(
            [k for k in pressed if k in phase_keys],
            ready=self._device_ready,
            replay_done=bool(getattr(self.device, "done", False)),
        )
        if transition is not None:
            self._enter(transition)
            if self.phase is Phase.QUIT:
                return
        command = self._command([k for k in pressed if k not in phase_keys])
        if self.writer is not None and self.phase in (Phase.TELEOP, Phase.REPLAY):
            self.writer.append(self.env.rmb_step_data(command))
        _, _, _, _, info = self.env.step(command)
        self.success = bool(info.get("is_success", False))
        self.result.steps += 1
        self._pace()

    def _command(self, device_keys: list[str]) -> np.ndarray:
        assert self.tracker is not None
        if not self.machine.driving:
            return self.tracker.command.copy()
        if isinstance(self.device, KeyDriven):
            self.device.feed(device_keys)
        return self.tracker.update(self.device.read())

    def _device_ready(self) -> bool:
        measured = self.env.measured_joint_pos()
        arms = [measured[joints] for joints, _ in self.env.robot.joint_slices()]
        ready = self.device.is_ready(arms)
        if not ready:
            reason = getattr(self.device, "not_ready_reason", "")
            self.log(reason or f"{self.device.name} is not ready: move it to the robot's pose")
        return ready

    def _pace(self) -> None:
        if not self.config.realtime:
            return
        period = self.env.control_dt
        self._deadline += period
        delay = self._deadline - self.clock()
        if delay > 0:
            self.sleep(delay)
        elif delay < -period:  # fell behind (a slow step): do not rush to catch up
            self._deadline = self.clock()

    # ------------------------------------------------------------------ phases
    def _enter(self, transition: Transition) -> None:
        phase = transition.phase
        if phase is Phase.QUIT:
            self._discard()
        elif phase in (Phase.SYNC, Phase.TELEOP, Phase.REPLAY) and transition.previous in (
            Phase.STANDBY,
            Phase.INITIAL,
        ):
            assert self.tracker is not None
            self.tracker.sync()  # the device starts from the robot's current command
            if phase is Phase.REPLAY:
                self.device.restart()  # type: ignore[attr-defined]
        if phase is Phase.TELEOP or (phase is Phase.REPLAY and self.config.save_replay):
            self._open_writer()
        if transition.previous in (Phase.END, Phase.END_REPLAY) and phase is Phase.INITIAL:
            self._finish(transition.save)
            if transition.previous is Phase.END_REPLAY:
                self._replays += 1
            if self._done():
                self.machine.phase = Phase.QUIT
                self.log(PROMPTS[Phase.QUIT])
                return
            self._reset()
        self.log(PROMPTS[self.phase])

    def _done(self) -> bool:
        config = self.config
        if config.replay:
            return self._replays >= config.replay_repeat
        return config.max_episodes is not None and len(self.result.saved) >= config.max_episodes

    def _reset(self) -> None:
        options = {}
        world = self._world_idx()
        if world is not None:
            options["world_idx"] = world
        self.env.reset(seed=self.config.seed + self._resets, options=options)
        self._resets += 1
        self.success = False
        self.tracker = CommandTracker(self.env)
        self.log(f"reset into world {self.env.world_idx}")

    def _world_idx(self) -> int | None:
        if self.config.replay:
            return int(getattr(self.device, "world_idx", 0))
        worlds = self.config.world_idx
        return None if not worlds else worlds[len(self.result.saved) % len(worlds)]

    # ------------------------------------------------------------------ episodes
    def _open_writer(self) -> None:
        self._discard()
        path = self.next_path()
        attrs = {**self.env.rmb_attrs(), K.ATTR_DEMO_NAME: path.stem}
        if self.config.task_desc:
            attrs[K.ATTR_TASK_DESC] = self.config.task_desc
        self.writer = EpisodeWriter(path, attrs, depth_codec=self.config.depth_codec)

    def next_path(self) -> Path:
        """Where the next episode goes: ``<demo>_world<idx>_<NNN>.<rmb|hdf5>``, NNN one past
        the highest number of this demo's episodes already in ``out``."""
        config = self.config
        demo = config.demo_name or self.env.rmb_env_name
        suffix = EpisodeFormat.from_name(config.fmt).short_name
        pattern = re.compile(rf"{re.escape(demo)}_world\d+_(\d+)\.(?:rmb|hdf5)")
        numbers = [
            int(match.group(1))
            for entry in config.out.iterdir()
            if (match := pattern.fullmatch(entry.name))
        ]
        index = max(numbers, default=-1) + 1
        return config.out / f"{demo}_world{self.env.world_idx}_{index:03d}.{suffix}"

    def _finish(self, save: bool) -> None:
        writer, self.writer = self.writer, None
        if writer is None:
            return
        if len(writer) == 0:
            writer.abort()
            self.log("nothing recorded: no episode written")
            return
        if save and self.config.save_success_only and not self.success:
            self.log("the task did not succeed and --save-success-only is set: discarded")
            save = False
        if save:
            self.result.saved.append(writer.close())
            self.log(f"saved {writer.path} ({len(writer)} steps)")
        else:
            writer.abort()
            self.result.discarded += 1
            self.log("episode discarded")

    def _discard(self) -> None:
        writer, self.writer = self.writer, None
        if writer is not None:
            writer.abort()
            self.result.discarded += 1
