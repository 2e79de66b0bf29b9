"""The watchdog: armed, it stops the arm once when commands stop arriving, and refuses every
command after until ``resume()``.

With the default 0.2 s timeout, a 50 Hz step (duration 0.02 s) must be followed by the next
command within 0.02 + 0.2 = 0.22 s.
"""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest

from rmb_lerobot.envs.real.errors import WatchdogTripped
from rmb_lerobot.envs.real.limits import limits_for
from rmb_lerobot.envs.real.safety import SafetyLayer
from rmb_lerobot.envs.real.testing import FakeArm, FakeClock
from rmb_lerobot.envs.real.watchdog import Watchdog

HOME = np.deg2rad([0.0, -30.0, 0.0, 45.0, 0.0, 75.0, 0.0])


@pytest.fixture
def clock():
    return FakeClock()


@pytest.fixture
def arm():
    return FakeArm(HOME)


@pytest.fixture
def layer(arm, clock):
    with SafetyLayer(arm, limits_for("xarm7"), clock=clock, watchdog_thread=False) as layer:
        yield layer


def test_commands_within_the_timeout_keep_it_quiet(layer, arm, clock):
    layer.arm_watchdog()
    clock.advance(0.2)  # the first command is due within 0.2 s of arming
    for _ in range(20):
        layer.step(HOME, 0.0)
        clock.advance(0.22)  # late by 50 Hz standards, still within 0.02 + 0.2 s
    assert arm.stops == 0 and len(arm.commands) == 20


def test_a_late_command_stops_the_arm_once_and_is_refused(layer, arm, clock):
    layer.arm_watchdog()
    layer.step(HOME, 0.0)
    clock.advance(0.25)  # > 0.02 + 0.2 s
    with pytest.raises(WatchdogTripped, match=r"no command for 0.2 s.*resume\(\)"):
        layer.step(HOME, 0.0)
    with pytest.raises(WatchdogTripped):
        layer.move_to(HOME)
    assert arm.stops == 1  # once, not once per refused command
    assert len(arm.commands) == 1
    layer.resume()
    layer.step(HOME, 0.0)
    assert len(arm.commands) == 2 and arm.stops == 1


def test_disarmed_it_never_trips(layer, arm, clock):
    layer.step(HOME, 0.0)
    clock.advance(60.0)
    layer.step(HOME, 0.0)
    with layer.streaming():
        layer.step(HOME, 0.0)
    clock.advance(60.0)
    layer.step(HOME, 0.0)
    assert arm.stops == 0


def test_a_reset_move_holds_it_off_for_its_duration(layer, arm, clock):
    layer.arm_watchdog()
    sent = layer.move_to(np.zeros(7))  # 75 deg at 18 deg/s: 4.17 s
    assert sent.duration == pytest.approx(75 / 18)
    clock.advance(sent.duration + 0.19)
    layer.step(np.zeros(7), 0.0)
    clock.advance(0.23)
    with pytest.raises(WatchdogTripped):
        layer.step(np.zeros(7), 0.0)


def test_the_timeout_comes_from_the_limits(arm, clock):
    limits = limits_for("xarm7", watchdog_timeout=0.06)  # 3 periods at 50 Hz
    layer = SafetyLayer(arm, limits, clock=clock, watchdog_thread=False)
    layer.arm_watchdog()
    layer.step(HOME, 0.0)
    clock.advance(0.09)
    with pytest.raises(WatchdogTripped, match=r"0\.06 s"):
        layer.step(HOME, 0.0)


def test_the_thread_stops_the_arm_with_no_command_at_all():
    stopped = threading.Event()
    arm = FakeArm(HOME)
    arm.stop = lambda: (stopped.set(), setattr(arm, "stops", arm.stops + 1))
    limits = limits_for("xarm7", watchdog_timeout=0.05)
    layer = SafetyLayer(arm, limits)  # real clock, background thread
    layer.arm_watchdog()
    layer.step(HOME, 0.0)
    started = time.monotonic()
    assert stopped.wait(timeout=5.0), "the watchdog thread never stopped the arm"
    assert time.monotonic() - started >= 0.05
    time.sleep(0.1)
    assert arm.stops == 1
    with pytest.raises(WatchdogTripped):
        layer.step(HOME, 0.0)
    thread = layer.watchdog._thread
    layer.close()
    assert thread is not None and not thread.is_alive()


def test_the_thread_sleeps_while_disarmed_and_close_joins_it():
    trips = []
    watchdog = Watchdog(0.01, lambda: trips.append(1))
    watchdog.arm()
    watchdog.disarm()
    time.sleep(0.05)
    thread = watchdog._thread
    watchdog.close()
    watchdog.close()
    assert trips == [] and thread is not None and not thread.is_alive()


def test_a_failing_stop_is_kept_not_raised_in_the_thread():
    def on_trip():
        raise RuntimeError("socket gone")

    watchdog = Watchdog(0.01, on_trip)
    watchdog.arm()
    deadline = time.monotonic() + 5.0
    while not watchdog.tripped and time.monotonic() < deadline:
        time.sleep(0.005)
    watchdog.close()
    assert watchdog.tripped and isinstance(watchdog.trip_error, RuntimeError)


def test_poll_trips_once_just_past_the_deadline(clock):
    trips = []
    watchdog = Watchdog(0.1, lambda: trips.append(1), clock=clock, thread=False)
    watchdog.arm()
    clock.advance(0.1)
    assert not watchdog.poll()  # exactly on time is on time
    clock.advance(0.001)
    assert watchdog.poll() and watchdog.poll()
    assert trips == [1]
    watchdog.resume()
    assert not watchdog.poll() and not watchdog.tripped
