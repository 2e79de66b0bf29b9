"""control_rate: the control rate from RMB's ``time`` key, checked for gaps and units."""

import numpy as np
import pytest

from rmb_lerobot import RmbFormatError
from rmb_lerobot.episode.timing import control_rate

SIM_HZ = 31.25  # RMB's MuJoCo UR5e envs: 0.004 s x 8


def test_simulated_clock_gives_its_exact_rate():
    assert control_rate(np.arange(200) / SIM_HZ) == pytest.approx(SIM_HZ)


def test_a_jittery_real_robot_clock_is_accepted_and_gives_the_mean_rate():
    """RMB's real envs: a 50 Hz loop whose steps wait for 30 fps cameras and the robot."""
    rng = np.random.default_rng(0)
    dt = 0.02 + rng.uniform(0, 0.015, 500)  # late by up to 15 ms every step
    dt[rng.choice(500, 10, replace=False)] += 0.033  # a missed camera frame now and then
    dt[rng.choice(500, 10, replace=False)] = 0.004  # a short step after a late one
    time = np.concatenate([[0.0], np.cumsum(dt)])
    assert control_rate(time) == pytest.approx(500 / time[-1])


def test_a_gap_in_the_recording_names_its_step_and_duration(tmp_path):
    time = np.arange(100) / SIM_HZ
    time[40:] += 0.3 - 1 / SIM_HZ  # one 0.3 s step at 31.25 Hz (the mean would say 25.4 Hz)
    with pytest.raises(
        RmbFormatError, match=r"jumps by 0\.3 s at step 40.*median step of 0\.032"
    ) as info:
        control_rate(time, path=tmp_path / "demo.rmb")
    assert info.value.key == "time" and info.value.path == tmp_path / "demo.rmb"


def test_time_in_milliseconds_is_refused_with_a_hint():
    with pytest.raises(RmbFormatError, match=r"0\.03125 Hz.*milliseconds\?"):
        control_rate(np.arange(100) * 32.0)


def test_implausibly_fast_rates_are_refused():
    with pytest.raises(RmbFormatError, match=r"expected seconds at 1 to 1000 Hz"):
        control_rate(np.arange(100) * 1e-6)


def test_time_that_does_not_increase_names_the_step():
    time = np.arange(10) / SIM_HZ
    time[6] = time[5]
    with pytest.raises(RmbFormatError, match=r"does not increase at step 6"):
        control_rate(time)


def test_non_finite_or_too_short_time_is_refused():
    with pytest.raises(RmbFormatError, match=r"holds nan at step 3"):
        control_rate(np.array([0.0, 0.032, 0.064, np.nan, 0.128]))
    with pytest.raises(RmbFormatError, match=r"at least two"):
        control_rate(np.array([0.0]))


def test_the_step_limit_can_be_loosened():
    time = np.concatenate([np.arange(50), 53 + np.arange(50)]) / SIM_HZ  # one 4-period step
    with pytest.raises(RmbFormatError, match="jumps"):
        control_rate(time)
    assert control_rate(time, max_step_ratio=5) == pytest.approx(99 / time[-1])
