"""Property-based tests: random command streams against the safety layer.

Each example drives a UR5e or an xArm7 (a fake arm that follows only part of the way, starting
anywhere, sometimes outside its bounds) with a random stream of steps, resets, reads and
watchdog calls: targets near the arm, far away, absurd, NaN or infinite; any gripper value,
duration and scale; planted faults (a timestamp that stops or goes backwards, a NaN reading)
and a clock that jumps. What the fake arm *received* is then checked against the limits,
recomputed here from the numbers and not from the layer's code:

- every joint target is finite and inside its bounds, or (where the arm was outside them)
  between the arm and the bound;
- no joint moves further from the measured position than ``clip(scale, 0.01, 10) * v_lim *
  duration`` on a step, ``max(that, v_lim) * duration`` on a reset;
- no step of under 0.1 s was asked to jump more than 90 deg;
- the gripper value is finite and in 0..255, the duration finite and in (0, 10] s;
- the TCP is in the workspace box, or no further out than the arm was;
- the reading a command was judged on was finite, not older than the last accepted one, not
  repeated for 5 reads or 0.1 s;
- with the watchdog armed, no command went out later than its deadline, nor after a trip until
  ``resume()``;
- a call either returns exactly what the arm received or raises a :class:`SafetyError` having
  sent nothing (and stopped the arm).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rmb_lerobot.envs.real.driver import ArmState
from rmb_lerobot.envs.real.errors import LayerClosed, SafetyError, WatchdogTripped
from rmb_lerobot.envs.real.limits import SafetyLimits, WorkspaceBox, limits_for, ur5e_tcp_fk
from rmb_lerobot.envs.real.safety import SafetyLayer, SentCommand
from rmb_lerobot.envs.real.testing import FakeArm, FakeClock

# Deterministic and quick: the same examples every run, nothing written to disk.
PROPERTY_SETTINGS = settings(
    max_examples=30,
    derandomize=True,
    database=None,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)

V_LIM = {"ur5e": np.deg2rad(191.0), "xarm7": np.deg2rad(180.0)}
BOUNDS_DEG = {
    "ur5e": ([-360, -360, -180, -360, -360, -360], [360, 360, 180, 360, 360, 360]),
    "xarm7": ([-360, -118, -360, -11, -360, -97, -360], [360, 120, 360, 225, 360, 180, 360]),
}
EPS = 1e-9
NONFINITE = [np.nan, np.inf, -np.inf]


def xarm7_toy_fk(q: np.ndarray) -> np.ndarray:
    """An injected FK for the xArm7 (any smooth map will do for the property)."""
    reach = 0.3 + 0.3 * np.cos(q[1]) + 0.2 * np.cos(q[1] + q[3])
    return np.array(
        [np.cos(q[0]) * reach, np.sin(q[0]) * reach, 0.3 + 0.3 * np.sin(q[1]) + 0.1 * q[5]]
    )


# -- the stream -------------------------------------------------------------------------------

finite_or_not = st.one_of(st.floats(-1e3, 1e3), st.sampled_from(NONFINITE))


def mostly(draw, good, bad, one_in: int):
    """Draw from ``good``, or from ``bad`` once in ``one_in`` draws (so streams go on)."""
    # The bad value sits last: hypothesis favours (and shrinks towards) the first entries.
    return draw(bad) if draw(st.sampled_from(range(one_in))) == one_in - 1 else draw(good)


@st.composite
def joint_request(draw, n: int):
    """(how, values): offsets from the arm, absolute targets, or garbage."""
    kinds = st.sampled_from(["near", "near", "near", "near", "far", "absolute", "huge"])
    how = mostly(draw, kinds, st.just("bad"), 15)
    if how == "near":
        return how, np.array(draw(st.lists(st.floats(-0.2, 0.2), min_size=n, max_size=n)))
    if how == "far":
        return how, np.array(draw(st.lists(st.floats(-3.0, 3.0), min_size=n, max_size=n)))
    if how == "absolute":
        return how, np.array(draw(st.lists(st.floats(-8.0, 8.0), min_size=n, max_size=n)))
    if how == "huge":
        return how, np.array(draw(st.lists(st.floats(-1e9, 1e9), min_size=n, max_size=n)))
    values = np.array(draw(st.lists(st.floats(-1.0, 1.0), min_size=n, max_size=n)))
    values[draw(st.integers(0, n - 1))] = draw(st.sampled_from(NONFINITE))
    return how, values


@st.composite
def operation(draw, n: int):
    """One call on the layer, with a planted fault and a clock advance before it."""
    kind = draw(
        st.sampled_from(["step"] * 12 + ["move_to", "read", "arm", "disarm", "resume", "wait"])
    )
    op = {
        "kind": kind,
        "fault": mostly(
            draw,
            st.just("none"),
            st.sampled_from(["hold2", "hold4", "hold6", "hold6", "hold9", "rewind", "nan_state"]),
            8,
        ),
        # 50 Hz; or two reads per period (where the stale read count binds before its time).
        "advance": mostly(draw, st.sampled_from([0.02, 0.01, 0.005]), st.floats(0.0, 0.3), 5),
    }
    if kind not in ("step", "move_to"):
        return op
    return {
        **op,
        "joints": draw(joint_request(n)),
        "gripper": mostly(draw, st.floats(-100.0, 1000.0), st.sampled_from(NONFINITE), 15),
        "reset_gripper": draw(st.booleans()),
        "duration": mostly(
            draw,
            st.one_of(st.sampled_from([0.02, 0.02, 0.02, 0.05, 0.1, 0.15]), st.floats(0.0, 11.0)),
            st.one_of(st.floats(-1.0, 0.0), st.sampled_from(NONFINITE)),
            15,
        ),
        "scale": mostly(
            draw, st.one_of(st.none(), st.floats(-1.0, 20.0)), st.sampled_from(NONFINITE), 20
        ),
    }


@st.composite
def scenario(draw, robot: str, workspace: bool):
    low, high = (np.deg2rad(b) for b in BOUNDS_DEG[robot])
    n = len(low)
    # Mostly inside the bounds; sometimes a joint up to 0.3 rad outside.
    start = np.array(
        [draw(st.floats(lo + 0.05, hi - 0.05)) for lo, hi in zip(low, high, strict=True)]
    )
    if draw(st.booleans()):
        j = draw(st.integers(0, n - 1))
        start[j] = draw(st.sampled_from([low[j], high[j]])) + draw(st.floats(-0.3, 0.3))
    return {
        "robot": robot,
        "start": start,
        "track": draw(st.floats(0.3, 1.0)),
        "workspace": workspace,
        "ops": draw(st.lists(operation(n), min_size=5, max_size=30)),
    }


# -- the harness ------------------------------------------------------------------------------


class LoggingArm(FakeArm):
    """A fake arm that also logs, per reading, the layer's clock at the time."""

    def __init__(self, clock: FakeClock, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.clock = clock
        self.reads: list[tuple[float, ArmState]] = []

    def read(self) -> ArmState:
        state = super().read()
        self.reads.append((self.clock(), state))
        return state


@dataclass
class WatchdogModel:
    """When the next command is due, as the spec says (not as the layer computes it)."""

    timeout: float
    armed: bool = False
    tripped: bool = False
    due: float = 0.0

    def arm(self, now: float) -> None:
        self.armed, self.due = True, now + self.timeout

    def sent(self, now: float, duration: float) -> None:
        self.due = now + duration + self.timeout


def outside(x: np.ndarray, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    return np.maximum(np.maximum(low - x, x - high), 0.0)


def make_layer(sc: dict, clock: FakeClock) -> tuple[SafetyLayer, LoggingArm]:
    robot, start = sc["robot"], sc["start"]
    box = None
    if sc["workspace"]:
        fk = ur5e_tcp_fk(0.15) if robot == "ur5e" else xarm7_toy_fk
        tcp = np.asarray(fk(start))[:3]
        box = WorkspaceBox(tuple(tcp - 0.25), tuple(tcp + 0.25), fk)
    arm = LoggingArm(clock, start, track=sc["track"])
    layer = SafetyLayer(arm, limits_for(robot, workspace=box), clock=clock, watchdog_thread=False)
    return layer, arm


def request(op: dict, arm: FakeArm) -> np.ndarray:
    how, values = op["joints"]
    return arm.joint_pos + values if how in ("near", "far", "bad") else values


def plant(op: dict, arm: FakeArm) -> None:
    fault = op["fault"]
    if fault.startswith("hold"):
        arm.hold_timestamp = int(fault[4:])
    elif fault == "rewind":
        arm.rewind = 0.001
    elif fault == "nan_state":
        arm.nan_joint = 0


def check_reading(lim: SafetyLimits, arm: LoggingArm, judged: ArmState, accepted: list) -> None:
    """The reading a command went out on: finite, fresh, not older than the last accepted."""
    assert np.all(np.isfinite(judged.joint_pos)) and np.all(np.isfinite(judged.joint_vel))
    assert np.isfinite(judged.gripper) and np.isfinite(judged.timestamp)
    if accepted:
        assert judged.timestamp >= accepted[-1]
    # The run of readings with this timestamp, up to this one.
    run = []
    for t, state in reversed(arm.reads):
        if state.timestamp != judged.timestamp:
            break
        run.append(t)
    assert len(run) <= lim.max_stale_reads  # the first plus at most max - 1 repeats
    assert run[0] - run[-1] <= lim.stale_timeout + EPS
    accepted.append(judged.timestamp)


def check_command(sc, lim, op, q_req, judged, sent_q, duration, scale) -> None:
    robot = sc["robot"]
    low, high = (np.deg2rad(b) for b in BOUNDS_DEG[robot])
    q_m = np.asarray(judged.joint_pos)
    # Finite, duration in range.
    assert np.all(np.isfinite(sent_q))
    assert np.isfinite(duration) and 0.0 < duration <= 10.0
    # Position bounds (or moving back towards them).
    out_sent, out_meas = outside(sent_q, low, high), outside(q_m, low, high)
    assert np.all((out_sent == 0) | (out_sent <= out_meas + EPS)), (sent_q, q_m)
    # Velocity.
    v = float(np.clip(2.0 if scale is None else scale, 0.01, 10.0)) * V_LIM[robot]
    if op["kind"] == "move_to":
        v = max(v, V_LIM[robot])
        assert duration >= 0.1 - EPS
    else:
        assert duration == op["duration"]
        if duration < 0.1:
            assert np.max(np.abs(q_req - q_m)) <= np.deg2rad(90.0) + EPS
    assert np.all(np.abs(sent_q - q_m) <= v * duration * (1 + 1e-12) + EPS)
    # Workspace.
    box = lim.workspace
    if box is not None:
        start_out = box.distance(box.tcp(q_m))
        assert box.distance(box.tcp(sent_q)) <= start_out + EPS


def run_scenario(sc: dict) -> int:
    clock = FakeClock()
    layer, arm = make_layer(sc, clock)
    lim = layer.limits
    model = WatchdogModel(lim.watchdog_timeout)
    accepted: list[float] = []
    sent_count = 0
    layer.connect()
    accepted.append(layer.last_state.timestamp)
    for op in sc["ops"]:
        clock.advance(op["advance"])
        plant(op, arm)
        kind, now = op["kind"], clock()
        if kind == "wait":
            continue
        if kind in ("arm", "resume"):
            getattr(layer, "arm_watchdog" if kind == "arm" else "resume")()
            model.arm(now)
            model.tripped = model.tripped and kind == "arm"
            continue
        if kind == "disarm":
            layer.disarm_watchdog()
            model.armed = False
            continue
        if kind == "read":
            reads_before = len(accepted)
            try:
                state = layer.read()
            except SafetyError:
                continue
            check_reading(lim, arm, state, accepted)
            assert len(accepted) > reads_before
            continue

        q_req = request(op, arm)
        n_cmd, n_grip, n_stop = len(arm.commands), len(arm.gripper_commands), arm.stops
        scale = op["scale"]
        try:
            if kind == "step":
                result = layer.step(q_req, op["gripper"], duration=op["duration"], scale=scale)
            else:
                grip = op["gripper"] if op["reset_gripper"] else None
                result = layer.move_to(q_req, gripper=grip, scale=scale)
        except SafetyError as exc:
            # Refused: nothing sent; the arm stopped (a trip stops it once, in the watchdog).
            assert len(arm.commands) == n_cmd and len(arm.gripper_commands) == n_grip
            assert not isinstance(exc, LayerClosed)
            if isinstance(exc, WatchdogTripped):
                # Tripped before (disarming does not clear a trip), or late now.
                assert model.tripped or (model.armed and now > model.due)
                model.tripped = True
            else:
                assert arm.stops == n_stop + 1
            continue
        # Sent: exactly one joint command (and the gripper), the same as returned.
        assert isinstance(result, SentCommand)
        assert len(arm.commands) == n_cmd + 1
        received = arm.commands[-1]
        np.testing.assert_array_equal(received.joint_pos, result.joint_pos)
        assert received.duration == result.duration
        assert received.measured is result.measured
        if result.gripper is None:
            assert len(arm.gripper_commands) == n_grip and kind == "move_to"
        else:
            assert len(arm.gripper_commands) == n_grip + 1
            g = arm.gripper_commands[-1]
            assert g == result.gripper and np.isfinite(g) and 0.0 <= g <= 255.0
        # The watchdog: not tripped, not late.
        if model.armed:
            assert not model.tripped and now <= model.due + EPS
        model.sent(now, result.duration)
        check_reading(lim, arm, received.measured, accepted)
        check_command(sc, lim, op, q_req, received.measured, received.joint_pos,
                      received.duration, scale)  # fmt: skip
        sent_count += 1
    layer.close()
    assert arm.closed
    return sent_count


@pytest.mark.parametrize("workspace", [False, True], ids=["no_box", "box"])
@pytest.mark.parametrize("robot", ["ur5e", "xarm7"])
def test_no_command_that_leaves_the_layer_breaks_a_limit(robot, workspace):
    @PROPERTY_SETTINGS
    @given(scenario(robot, workspace))
    def check(sc):
        run_scenario(sc)

    check()


def test_the_streams_do_send_commands():
    """Guard against a vacuous property: well-formed steps go through."""
    step = {
        "kind": "step",
        "joints": ("near", np.full(6, 0.2)),
        "gripper": 100.0,
        "reset_gripper": True,
        "duration": 0.02,
        "scale": None,
        "fault": "none",
        "advance": 0.02,
    }
    sc = {"robot": "ur5e", "start": np.zeros(6), "track": 0.5, "workspace": False}
    assert run_scenario({**sc, "ops": [step] * 10}) == 10
