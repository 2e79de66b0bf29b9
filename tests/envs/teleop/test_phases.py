"""RMB's phase machine: which key moves where."""

from __future__ import annotations

from rmb_lerobot.envs.teleop.phases import Phase, PhaseMachine


def walk(machine: PhaseMachine, *steps: str, **kwargs) -> list[Phase]:
    """The phase after each step's key ("" for a step without a key)."""
    phases = []
    for key in steps:
        machine.advance([key] if key else [], **kwargs)
        phases.append(machine.phase)
    return phases


def test_recording_phases_and_save():
    machine = PhaseMachine()
    assert walk(machine, "w", "n", "n", "s", "n") == [
        Phase.INITIAL,
        Phase.STANDBY,
        Phase.TELEOP,
        Phase.TELEOP,  # s moves -x while recording: it never saves here
        Phase.END,
    ]
    assert machine.advance(["x", "s"]).save is True
    assert machine.phase is Phase.INITIAL


def test_discard_sync_and_quit():
    machine = PhaseMachine(sync_before_record=True)
    assert walk(machine, "n", "n", "n", "n", "f") == [
        Phase.STANDBY,
        Phase.SYNC,
        Phase.TELEOP,
        Phase.END,
        Phase.INITIAL,
    ]
    machine.advance(["n"])
    transition = machine.advance(["esc"])
    assert transition.previous is Phase.STANDBY and machine.phase is Phase.QUIT


def test_standby_waits_for_the_device():
    machine = PhaseMachine(phase=Phase.STANDBY)
    assert machine.advance(["n"], ready=lambda: False) is None
    assert machine.advance(["n"], ready=lambda: True).phase is Phase.TELEOP


def test_keys_a_phase_does_not_listen_to_go_to_the_device():
    machine = PhaseMachine(phase=Phase.TELEOP)
    assert machine.keys == {"n", "esc"} and machine.driving
    machine.phase = Phase.END
    assert machine.keys == {"s", "f", "esc"} and not machine.driving


def test_replay_phases_manual_and_automatic():
    machine = PhaseMachine(replay=True)
    assert walk(machine, "", "n", "", "h", "n") == [
        Phase.INITIAL,
        Phase.REPLAY,
        Phase.REPLAY,
        Phase.END_REPLAY,
        Phase.INITIAL,
    ]
    auto = PhaseMachine(replay=True, auto=True)
    assert walk(auto, "", "") == [Phase.REPLAY, Phase.REPLAY]
    assert walk(auto, "", "", replay_done=True) == [Phase.END_REPLAY, Phase.INITIAL]
