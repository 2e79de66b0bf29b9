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

With ``parallel_envs`` the same joint command also drives further envs, each recording its own
episode (:mod:`~rmb_lerobot.envs.teleop.parallel`); a ``view``
(:mod:`~rmb_lerobot.envs.teleop.live_view`) is sent env 0's images, the targets and the phase
after each step.
"""

from __future__ import annotations

import logging
import re
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol, runtime_checkable

import numpy as np

from rmb_lerobot.envs.base import RmbEnv
from rmb_lerobot.envs.interrupts import raise_if_signalled, recording
from rmb_lerobot.envs.teleop.command import CommandTracker
from rmb_lerobot.envs.teleop.device import InputDevice, KeySource
from rmb_lerobot.envs.teleop.parallel import Lane, lane_seed, lane_world
from rmb_lerobot.envs.teleop.phases import PROMPTS, Phase, PhaseMachine, Transition
from rmb_lerobot.episode import EpisodeFormat

logger = logging.getLogger(__name__)


@runtime_checkable
class StepView(Protocol):
    """Where the loop shows each step (the live view)."""

    def log_step(self, session: TeleopSession) -> None:
        """Show the session's state after a step."""
        ...


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
        max_episodes: Quit after this many kept demonstrations (None: until Esc); with
            parallel envs a demonstration is kept when any of its episodes is.
        replay: Run the replay phases (the device is a replayed log).
        auto_replay: Replay without waiting for ``n``.
        save_replay: Record each replay as an episode.
        replay_repeat: Replays before quitting.
        depth_codec: Depth video codec of the compact format.
        background_encoding: Encode the compact format's images on a background thread
            (the default; off encodes in the loop's thread, as before: the rate benchmark
            measures both).
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
    background_encoding: bool = True


@dataclass
class TeleopResult:
    """What a session did."""

    saved: list[Path] = field(default_factory=list)
    discarded: int = 0  # episodes recorded and not kept (f, failure with success-only, Esc)
    steps: int = 0  # control steps run
    demos: int = 0  # demonstrations with at least one episode kept


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
        parallel_envs: Further sim envs driven by env 0's joint command, one episode each per
            demonstration (``rmb-teleop --num-envs``).
        view: Shown each step (the live view); None: nothing.
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
        parallel_envs: Sequence[RmbEnv] = (),
        view: StepView | None = None,
    ):
        self.env = env
        self.lanes = [Lane(e, k) for k, e in enumerate([env, *parallel_envs])]
        self.view = view
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
        self.result = TeleopResult()
        self._resets = 0
        self._replays = 0
        self._deadline = 0.0

    @property
    def phase(self) -> Phase:
        return self.machine.phase

    @property
    def success(self) -> bool:
        """Whether env 0's task has succeeded since its last reset."""
        return self.lanes[0].success

    @property
    def recording(self) -> bool:
        """Whether this step is recorded (teleop, or a replay being saved)."""
        return self.lanes[0].writer is not None and self.phase in (Phase.TELEOP, Phase.REPLAY)

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
        recording = self.recording
        for lane in self.lanes:
            lane.record_and_step(command, recording)
        self.result.steps += 1
        if self.view is not None:
            self.view.log_step(self)
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
        return config.max_episodes is not None and self.result.demos >= config.max_episodes

    def _reset(self) -> None:
        for lane in self.lanes:
            options = {}
            world = self._world_idx(lane.index)
            if world is not None:
                options["world_idx"] = world
            seed = lane_seed(self.config.seed, self._resets, lane.index, len(self.lanes))
            lane.env.reset(seed=seed, options=options)
            lane.success = False
        self._resets += 1
        self.tracker = CommandTracker(self.env)
        worlds = " ".join(str(lane.env.world_idx) for lane in self.lanes)
        self.log(f"reset into world{'s' if len(self.lanes) > 1 else ''} {worlds}")

    def _world_idx(self, lane: int = 0) -> int | None:
        num_worlds = int(self.env.task.num_worlds) if len(self.lanes) > 1 else 0
        if self.config.replay:  # the log's world, then the next ones for parallel envs
            world = int(getattr(self.device, "world_idx", 0))
            return world if lane == 0 else (world + lane) % num_worlds
        return lane_world(
            self.config.world_idx, num_worlds, self.result.demos, lane, len(self.lanes)
        )

    # ------------------------------------------------------------------ episodes
    def _open_writer(self) -> None:
        self._discard()
        for lane in self.lanes:
            path = self.next_path(lane.index)
            lane.open(
                path,
                self.config.task_desc,
                self.config.depth_codec,
                background_encoding=self.config.background_encoding,
            )

    def next_path(self, lane: int = 0) -> Path:
        """Where lane ``lane``'s next episode goes: ``<demo>_world<idx>_<NNN>.<rmb|hdf5>``, NNN
        one past the highest number of this demo's episodes already in ``out``, plus ``lane``
        (numbers of parallel episodes a failure discarded stay unused)."""
        config = self.config
        demo = config.demo_name or self.env.rmb_env_name
        suffix = EpisodeFormat.from_name(config.fmt).short_name
        pattern = re.compile(rf"{re.escape(demo)}_world\d+_(\d+)\.(?:rmb|hdf5)")
        numbers = [
            int(match.group(1))
            for entry in config.out.iterdir()
            if (match := pattern.fullmatch(entry.name))
        ]
        index = max(numbers, default=-1) + 1 + lane
        world = self.lanes[lane].env.world_idx
        return config.out / f"{demo}_world{world}_{index:03d}.{suffix}"

    def _finish(self, save: bool) -> None:
        kept = 0
        for lane in self.lanes:
            recorded = lane.writer is not None and len(lane.writer) > 0
            path, message = lane.finish(save, self.config.save_success_only)
            if message and len(self.lanes) > 1:
                message = f"env {lane.index}: {message}"
            if message:
                self.log(message)
            if path is not None:
                self.result.saved.append(path)
                kept += 1
            elif recorded:
                self.result.discarded += 1
        self.result.demos += kept > 0

    def _discard(self) -> None:
        for lane in self.lanes:
            self.result.discarded += lane.abort()
