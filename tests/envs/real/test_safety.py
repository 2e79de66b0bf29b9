"""The safety layer, rule by rule, with RMB's numbers worked out by hand.

UR5e at 50 Hz: v_lim = 191 deg/s, so a step of 0.02 s at RMB's scale 2.0 may move each joint
2.0 * 191 * 0.02 = 7.64 deg from where the arm was measured.
"""

from __future__ import annotations

import numpy as np
import pytest

from rmb_lerobot.envs.real.driver import ConnectionLost
from rmb_lerobot.envs.real.errors import (
    InvalidCommand,
    InvalidState,
    JumpTooLarge,
    LayerClosed,
    NonFiniteCommand,
    OutsideWorkspace,
    SafetyError,
    StaleReading,
)
from rmb_lerobot.envs.real.limits import WorkspaceBox, limits_for
from rmb_lerobot.envs.real.safety import SafetyLayer
from rmb_lerobot.envs.real.testing import FakeArm, FakeClock

DEG = np.pi / 180.0
# RMB's RealUR5eDemoEnv home (rad).
UR5E_HOME = np.array([1.18000162, -1.91696992, 1.5561803, -1.21203147, -1.57465679, -0.39695961])
XARM7_HOME = np.deg2rad([0.0, -30.0, 0.0, 45.0, 0.0, 75.0, 0.0])  # RealXarm7DemoEnv


@pytest.fixture
def clock():
    return FakeClock()


@pytest.fixture
def arm():
    return FakeArm(UR5E_HOME)


@pytest.fixture
def layer(arm, clock):
    with SafetyLayer(arm, limits_for("ur5e"), clock=clock, watchdog_thread=False) as layer:
        layer.connect()
        yield layer


def moved(q, joint, degrees):
    out = np.array(q, dtype=np.float64)
    out[joint] += degrees * DEG
    return out


# -- per-step velocity clamp ------------------------------------------------------------------


def test_a_small_step_is_sent_as_asked(layer, arm):
    target = moved(UR5E_HOME, 0, 5.0)  # 5 deg < 7.64 deg
    sent = layer.step(target, 10.0, duration=0.02)
    np.testing.assert_array_equal(sent.joint_pos, target)
    assert (sent.gripper, sent.duration, sent.clipped) == (10.0, 0.02, ())
    np.testing.assert_array_equal(arm.commands[-1].joint_pos, target)
    assert arm.commands[-1].duration == 0.02
    assert arm.gripper_commands == [10.0]


def test_a_step_is_clamped_to_scale_times_v_lim_times_dt(layer):
    sent = layer.step(moved(UR5E_HOME, 0, 20.0), 0.0, duration=0.02)
    step = sent.joint_pos - UR5E_HOME
    assert step[0] / DEG == pytest.approx(7.64)  # 2.0 * 191 deg/s * 0.02 s
    np.testing.assert_array_equal(step[1:], 0.0)
    (clip,) = sent.clipped
    assert (clip.rule, clip.name) == ("velocity", "shoulder_pan_joint")
    assert clip.requested == pytest.approx(UR5E_HOME[0] + 20 * DEG)


def test_the_clamp_is_per_joint_and_both_ways(layer):
    sent = layer.step(UR5E_HOME + np.array([-30, 3, 30, -3, 8, -8]) * DEG, 0.0, duration=0.02)
    np.testing.assert_allclose(
        (sent.joint_pos - UR5E_HOME) / DEG, [-7.64, 3, 7.64, -3, 7.64, -7.64]
    )
    assert [c.name for c in sent.clipped] == [
        "shoulder_pan_joint", "elbow_joint", "wrist_2_joint", "wrist_3_joint",
    ]  # fmt: skip


@pytest.mark.parametrize(
    "scale, degrees",
    [
        (1.0, 3.82),  # 1 * 191 * 0.02
        (100.0, 38.2),  # scale clipped to 10
        (0.0, 0.0382),  # scale clipped to 0.01
    ],
)
def test_the_scale_is_clipped_to_rmbs_range(layer, scale, degrees):
    sent = layer.step(moved(UR5E_HOME, 1, 80.0), 0.0, duration=0.02, scale=scale)
    assert (sent.joint_pos[1] - UR5E_HOME[1]) / DEG == pytest.approx(degrees)


def test_the_clamp_is_against_the_measured_position_not_the_last_command():
    arm = FakeArm(UR5E_HOME, track=0.5)  # the arm gets half way per command
    layer = SafetyLayer(arm, limits_for("ur5e"), clock=FakeClock(), watchdog_thread=False)
    layer.step(moved(UR5E_HOME, 0, 50.0), 0.0)  # sent +7.64, the arm reaches +3.82
    sent = layer.step(moved(UR5E_HOME, 0, 50.0), 0.0)
    assert (sent.joint_pos[0] - UR5E_HOME[0]) / DEG == pytest.approx(3.82 + 7.64)


# -- jump refusal -----------------------------------------------------------------------------


def test_a_jump_over_90_degrees_in_under_0_1_s_is_refused(layer, arm):
    with pytest.raises(JumpTooLarge) as info:
        layer.step(moved(UR5E_HOME, 2, 91.0), 0.0, duration=0.02)
    message = str(info.value)
    assert "elbow_joint" in message and "91.0°" in message and "90°" in message
    assert arm.commands == []
    assert arm.stops == 1  # a refusal stops the arm


def test_a_jump_just_under_90_degrees_is_clamped_not_refused(layer):
    sent = layer.step(moved(UR5E_HOME, 2, 89.0), 0.0, duration=0.02)
    assert (sent.joint_pos[2] - UR5E_HOME[2]) / DEG == pytest.approx(7.64)


def test_a_jump_over_90_degrees_is_allowed_with_0_1_s(layer):
    sent = layer.step(moved(UR5E_HOME, 0, 91.0), 0.0, duration=0.1)
    assert (sent.joint_pos[0] - UR5E_HOME[0]) / DEG == pytest.approx(38.2)  # 2 * 191 * 0.1


# -- joint position bounds --------------------------------------------------------------------


def test_ur5e_elbow_is_clamped_to_pi():
    start = UR5E_HOME.copy()
    start[2] = np.pi - 0.01
    layer = SafetyLayer(FakeArm(start), limits_for("ur5e"), watchdog_thread=False)
    target = start.copy()
    target[2] = np.pi + 0.05
    sent = layer.step(target, 0.0)
    assert sent.joint_pos[2] == np.pi
    assert [(c.rule, c.name) for c in sent.clipped] == [("position", "elbow_joint")]


def test_xarm7_j4_is_clamped_to_minus_11_degrees():
    start = XARM7_HOME.copy()
    start[3] = -10 * DEG
    layer = SafetyLayer(FakeArm(start), limits_for("xarm7"), watchdog_thread=False)
    sent = layer.step(moved(start, 3, -5.0), 0.0)  # asks -15 deg
    assert sent.joint_pos[3] / DEG == pytest.approx(-11.0)
    assert sent.clipped[0].name == "joint4"


def test_an_arm_outside_its_bounds_is_only_moved_back_towards_them():
    start = XARM7_HOME.copy()
    start[1] = -130 * DEG  # j2 bound is -118 deg: 12 deg outside
    layer = SafetyLayer(FakeArm(start), limits_for("xarm7"), watchdog_thread=False)
    sent = layer.step(start, 0.0)  # hold where it is
    # Clamped to the bound first, then to 2 * 180 deg/s * 0.02 s = 7.2 deg from the arm.
    assert sent.joint_pos[1] / DEG == pytest.approx(-130 + 7.2)


# -- gripper ----------------------------------------------------------------------------------


@pytest.mark.parametrize("asked, sent_value", [(300.0, 255.0), (-5.0, 0.0), (128.0, 128.0)])
def test_the_gripper_is_clamped_to_0_255(layer, arm, asked, sent_value):
    sent = layer.step(UR5E_HOME, asked)
    assert sent.gripper == arm.gripper_commands[-1] == sent_value
    assert ("gripper" in sent.clipped_rules) == (asked != sent_value)


# -- non-finite and malformed commands ----------------------------------------------------------


@pytest.mark.parametrize(
    "kwargs, error, match",
    [
        ({"joint_pos": moved(UR5E_HOME, 3, np.nan)}, NonFiniteCommand, "wrist_1_joint: .*nan"),
        ({"joint_pos": moved(UR5E_HOME, 5, np.inf)}, NonFiniteCommand, "wrist_3_joint: .*inf"),
        ({"gripper": np.nan}, NonFiniteCommand, "gripper nan"),
        ({"duration": np.inf}, NonFiniteCommand, "duration inf"),
        ({"scale": -np.inf}, NonFiniteCommand, "scale -inf"),
        ({"duration": 0.0}, InvalidCommand, r"duration 0.0 s is not in \(0, 10.0\]"),
        ({"duration": -0.02}, InvalidCommand, "duration -0.02"),
        ({"duration": 11.0}, InvalidCommand, "duration 11.0"),
        ({"joint_pos": UR5E_HOME[:5]}, InvalidCommand, r"shape \(5,\), expected \(6,\)"),
        ({"joint_pos": "home"}, InvalidCommand, "joint command 'home'"),
        ({"gripper": "open"}, InvalidCommand, "gripper 'open'"),
    ],
)
def test_bad_commands_are_refused_and_nothing_is_sent(layer, arm, kwargs, error, match):
    command = {"joint_pos": UR5E_HOME, "gripper": 0.0, "duration": 0.02, **kwargs}
    with pytest.raises(error, match=match):
        layer.step(**command)
    assert arm.commands == [] and arm.gripper_commands == []
    assert arm.stops == 1


# -- reset moves ------------------------------------------------------------------------------


def test_reset_duration_is_distance_over_scaled_v_lim(layer, arm):
    sent = layer.move_to(moved(UR5E_HOME, 4, 45.0), gripper=0.0)
    assert sent.duration == pytest.approx(45.0 / (0.3 * 191.0))  # 0.785 s
    np.testing.assert_allclose(sent.joint_pos, moved(UR5E_HOME, 4, 45.0))  # not clamped
    assert arm.commands[-1].duration == sent.duration


def test_reset_duration_is_at_least_0_1_s(layer):
    assert layer.move_to(moved(UR5E_HOME, 0, 1.0)).duration == 0.1


def test_reset_duration_is_at_most_10_s():
    layer = SafetyLayer(FakeArm(np.zeros(7)), limits_for("xarm7"), watchdog_thread=False)
    # 300 deg at xArm7's reset scale 0.1 (18 deg/s) would take 16.7 s: RMB caps it at 10 s.
    sent = layer.move_to(np.deg2rad([300, 0, 0, 0, 0, 0, 0]))
    assert sent.duration == 10.0
    assert sent.gripper is None


def test_reset_clamps_the_target_to_the_bounds(layer):
    target = UR5E_HOME.copy()
    target[2] = 4.0
    sent = layer.move_to(target)
    assert sent.joint_pos[2] == np.pi
    assert sent.duration == pytest.approx((np.pi - UR5E_HOME[2]) / (0.3 * 191 * DEG))


# -- state ------------------------------------------------------------------------------------


def test_a_timestamp_that_stops_for_5_reads_is_stale(layer, arm):
    arm.hold_timestamp = 10
    for _ in range(4):
        layer.read()  # 4 repeats are tolerated (two reads per period can share a stamp)
    with pytest.raises(StaleReading, match="not advanced for 5 reads"):
        layer.read()
    assert arm.stops == 1


def test_a_timestamp_that_stops_for_over_0_1_s_is_stale(layer, arm, clock):
    arm.hold_timestamp = 10
    clock.advance(0.05)
    layer.read()
    clock.advance(0.06)  # 0.11 s since the timestamp last advanced
    with pytest.raises(StaleReading, match=r"not advanced for 0.110 s \(limit 0.1 s\)"):
        layer.step(UR5E_HOME, 0.0)
    assert arm.commands == []


def test_a_timestamp_going_backwards_is_stale(layer, arm):
    arm.rewind = 1.0
    with pytest.raises(StaleReading, match="went backwards"):
        layer.read()


def test_a_fresh_reading_clears_the_stale_count(layer, arm):
    arm.hold_timestamp = 4
    for _ in range(4):
        layer.read()
    layer.read()  # advances
    arm.hold_timestamp = 4
    for _ in range(4):
        layer.read()


def test_a_nan_reading_is_refused_and_nothing_is_sent(layer, arm):
    arm.nan_joint = 1
    with pytest.raises(InvalidState, match="joint_pos of joint shoulder_lift_joint is nan"):
        layer.step(UR5E_HOME, 0.0)
    assert arm.commands == [] and arm.stops == 1


# -- workspace box ----------------------------------------------------------------------------


def cartesian(q):
    """A toy arm whose first three joints are the TCP's x, y, z (m)."""
    return np.asarray(q[:3])


@pytest.fixture
def boxed():
    lim = limits_for("ur5e", workspace=WorkspaceBox((-1.0, -1.0, 0.0), (1.0, 1.0, 1.0), cartesian))
    arm = FakeArm([0.9, 0.0, 0.5, 0.0, 0.0, 0.0])
    return SafetyLayer(arm, lim, watchdog_thread=False), arm


def test_a_step_out_of_the_box_is_refused(boxed):
    layer, arm = boxed
    layer.step([0.95, 0.0, 0.5, 0, 0, 0], 0.0)
    # 0.1 m of x is 5.7 deg of joint: 3 samples; the first one out is reported.
    with pytest.raises(OutsideWorkspace, match=r"TCP \[1.0167, 0.0, 0.5\] m at the path 2/3"):
        layer.step([1.05, 0.0, 0.5, 0, 0, 0], 0.0)
    assert len(arm.commands) == 1


def test_a_reset_whose_path_leaves_the_box_is_refused():
    """Both ends inside, the way between outside: x = sin(q0) passes 1 at q0 = 90 deg."""
    box = WorkspaceBox((-0.9, -1.0, -1.0), (0.9, 1.0, 1.0), lambda q: [np.sin(q[0]), *q[1:3]])
    arm = FakeArm(np.array([0.5, 0.0, 0.0, 0.0, 0.0, 0.0]))  # x = 0.479
    layer = SafetyLayer(arm, limits_for("ur5e", workspace=box), watchdog_thread=False)
    with pytest.raises(OutsideWorkspace, match=r"at the path \d+/\d+ to the target"):
        layer.move_to([np.pi - 0.5, 0, 0, 0, 0, 0])  # x = 0.479 again
    assert arm.commands == []


def test_an_arm_outside_the_box_may_move_back_but_not_further_out(boxed):
    layer, arm = boxed
    arm.joint_pos = np.array([1.2, 0.0, 0.5, 0.0, 0.0, 0.0])  # 0.2 m outside
    layer.step([1.15, 0.0, 0.5, 0, 0, 0], 0.0)  # 0.15 m outside: closer, allowed
    with pytest.raises(OutsideWorkspace, match=r"the arm is 0\.1500 m outside"):
        layer.step([1.2, 0.0, 0.5, 0, 0, 0], 0.0)


def test_the_ur5e_dh_fk_guards_a_floor():
    from rmb_lerobot.envs.real.limits import ur5e_tcp_fk

    fk = ur5e_tcp_fk(0.15)
    z = fk(UR5E_HOME)[2]
    box = WorkspaceBox((-2.0, -2.0, z - 0.005), (2.0, 2.0, 2.0), fk)
    layer = SafetyLayer(
        FakeArm(UR5E_HOME), limits_for("ur5e", workspace=box), watchdog_thread=False
    )
    lower = moved(UR5E_HOME, 1, 5.0)
    lower_z = fk(lower)[2]
    up, down = (1, -1) if lower_z > z else (-1, 1)
    layer.step(moved(UR5E_HOME, 1, 5.0 * up), 0.0)  # raises the TCP: fine
    with pytest.raises(OutsideWorkspace):
        layer.step(moved(layer.last_state.joint_pos, 1, 7.0 * down), 0.0)


# -- faults, lifecycle ------------------------------------------------------------------------


def test_a_driver_error_stops_the_arm_and_propagates(layer, arm):
    arm.fail_next_command = ConnectionLost("ur5e: connection lost in servoJ")
    with pytest.raises(ConnectionLost, match="servoJ"):
        layer.step(UR5E_HOME, 0.0)
    assert arm.stops == 1


def test_ctrl_c_inside_a_command_stops_the_arm(layer, arm):
    arm.fail_next_command = KeyboardInterrupt()
    with pytest.raises(KeyboardInterrupt):
        layer.move_to(UR5E_HOME)
    assert arm.stops == 1


def test_every_refusal_is_a_safety_error():
    for error in (InvalidCommand, NonFiniteCommand, JumpTooLarge, OutsideWorkspace, StaleReading):
        assert issubclass(error, SafetyError)


def test_close_closes_the_driver_and_refuses_commands_after(layer, arm):
    layer.close()
    layer.close()
    assert arm.closed
    with pytest.raises(LayerClosed):
        layer.step(UR5E_HOME, 0.0)


def test_zero_wrench_and_stop_go_to_the_driver(layer, arm):
    layer.zero_wrench()
    layer.stop()
    assert arm.calls[-2:] == ["zero_wrench", "stop"]


def test_the_layers_stale_state_is_also_the_drivers():
    from rmb_lerobot.envs.real import driver

    assert issubclass(StaleReading, driver.StaleState) and issubclass(StaleReading, SafetyError)
