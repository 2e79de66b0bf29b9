"""RMB's teleoperation phases and the keys that move between them (``TeleopBase``).

Recording::

    INITIAL --n--> STANDBY --n, device ready--> [SYNC --n-->] TELEOP --n--> END
    END --s--> INITIAL (episode saved; with save_success_only only a successful one)
    END --f--> INITIAL (episode discarded)

Replay (``--input-device replay``)::

    INITIAL --n (auto: at once)--> REPLAY --h, or the log's end--> END_REPLAY
    END_REPLAY --n (auto: at once)--> INITIAL

Esc quits from any phase (an episode being recorded is discarded). In SYNC the device drives
the robot unrecorded, so the operator can line it up first (RMB's ``--sync_before_record``);
TELEOP records every step before it is sent. The machine is pure: the loop
(:mod:`rmb_lerobot.envs.teleop.session`) does what a transition means.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from enum import StrEnum


class Phase(StrEnum):
    """Where a teleoperation session is."""

    INITIAL = "initial"
    STANDBY = "standby"
    SYNC = "sync"
    TELEOP = "teleop"
    END = "end"
    REPLAY = "replay"
    END_REPLAY = "end_replay"
    QUIT = "quit"


NEXT_KEY = "n"
SAVE_KEY = "s"
DISCARD_KEY = "f"
STOP_REPLAY_KEY = "h"
QUIT_KEY = "esc"

DRIVING_PHASES = frozenset({Phase.SYNC, Phase.TELEOP, Phase.REPLAY})
"""Phases in which the device moves the robot (elsewhere it holds its last command)."""

PHASE_KEYS: dict[Phase, frozenset[str]] = {
    Phase.INITIAL: frozenset({NEXT_KEY}),
    Phase.STANDBY: frozenset({NEXT_KEY}),
    Phase.SYNC: frozenset({NEXT_KEY}),
    Phase.TELEOP: frozenset({NEXT_KEY}),
    Phase.END: frozenset({SAVE_KEY, DISCARD_KEY}),
    Phase.REPLAY: frozenset({STOP_REPLAY_KEY}),
    Phase.END_REPLAY: frozenset({NEXT_KEY}),
    Phase.QUIT: frozenset(),
}
"""Keys each phase listens to, besides Esc. In a driving phase the other keys go to the device,
so RMB's S (move -x) never saves: ``s`` saves only in END."""

PROMPTS: dict[Phase, str] = {
    Phase.INITIAL: "initial: press n to start",
    Phase.STANDBY: "standby: press n when the device is ready to drive the robot",
    Phase.SYNC: "sync: the device drives the robot (not recorded); press n to record",
    Phase.TELEOP: "teleop: recording; press n to end the episode",
    Phase.END: "end: press s to save, f to discard",
    Phase.REPLAY: "replay: re-commanding the log; press h to stop",
    Phase.END_REPLAY: "end of replay: press n for the next one",
    Phase.QUIT: "quit",
}


@dataclass(frozen=True)
class Transition:
    """A phase change, and for END -> INITIAL whether the episode is to be kept."""

    previous: Phase
    phase: Phase
    save: bool = False


@dataclass
class PhaseMachine:
    """The phase of a session and its transitions on keys.

    Args:
        sync_before_record: Pass through SYNC between STANDBY and TELEOP.
        replay: Use the replay phases instead of the recording ones.
        auto: Replay only: start and end each replay without waiting for ``n``.
        phase: The starting phase.
    """

    sync_before_record: bool = False
    replay: bool = False
    auto: bool = False
    phase: Phase = Phase.INITIAL

    @property
    def keys(self) -> frozenset[str]:
        """The keys the current phase listens to (Esc included); others go to the device."""
        return PHASE_KEYS[self.phase] | {QUIT_KEY}

    @property
    def driving(self) -> bool:
        """Whether the device moves the robot in the current phase."""
        return self.phase in DRIVING_PHASES

    def advance(
        self,
        keys: Iterable[str],
        *,
        ready: Callable[[], bool] = lambda: True,
        replay_done: bool = False,
    ) -> Transition | None:
        """Apply this step's keys (the first one that changes the phase wins).

        Args:
            keys: Keys pressed this step, oldest first.
            ready: Whether the device may start driving (asked only on ``n`` in STANDBY).
            replay_done: The replayed log has no step left.

        Returns:
            The transition, or None when the phase stays.
        """
        keys = [key for key in keys if key in self.keys]
        if QUIT_KEY in keys:
            return self._go(Phase.QUIT)
        phase, pressed = self.phase, set(keys)
        if phase is Phase.INITIAL and (NEXT_KEY in pressed or (self.replay and self.auto)):
            return self._go(Phase.REPLAY if self.replay else Phase.STANDBY)
        if phase is Phase.STANDBY and NEXT_KEY in pressed and ready():
            return self._go(Phase.SYNC if self.sync_before_record else Phase.TELEOP)
        if phase is Phase.SYNC and NEXT_KEY in pressed:
            return self._go(Phase.TELEOP)
        if phase is Phase.TELEOP and NEXT_KEY in pressed:
            return self._go(Phase.END)
        if phase is Phase.END:
            for key in keys:
                if key in (SAVE_KEY, DISCARD_KEY):
                    return self._go(Phase.INITIAL, save=key == SAVE_KEY)
        if phase is Phase.REPLAY and (STOP_REPLAY_KEY in pressed or replay_done):
            return self._go(Phase.END_REPLAY)
        if phase is Phase.END_REPLAY and (NEXT_KEY in pressed or self.auto):
            return self._go(Phase.INITIAL, save=True)
        return None

    def _go(self, phase: Phase, save: bool = False) -> Transition:
        transition = Transition(self.phase, phase, save)
        self.phase = phase
        return transition
