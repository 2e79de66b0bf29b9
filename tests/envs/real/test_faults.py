"""Faults while an RMB episode is recorded on a real env (the twins' fault hooks).

Each fault happens mid-episode, injected by the command stream itself at step ``FAULT_AT``:
connection lost, an SDK error code, a protective stop, a gripper fault, stale state, a policy
emitting NaN, and Ctrl-C during a reset move. In each the arm is stopped (the twin's arm
comes to rest, or is held), the exception names what happened, and the episode is left out:
nothing at its path, no temporary left beside it.
"""

from __future__ import annotations

import _thread
import dataclasses
import threading

import numpy as np
import pytest

from rmb_lerobot.envs.real.config import make_real_env
from rmb_lerobot.envs.real.driver import ConnectionLost, GripperFault, ProtectiveStop, SdkError
from rmb_lerobot.envs.real.driver import StaleState as DriverStale
from rmb_lerobot.envs.real.errors import NonFiniteCommand

FAULT_AT = 5
BOUND_S = 15.0
FAST = {"driver": "sim", "camera_configs": {}, "settle_s": 0.02, "reset_scale": 1.0}


@pytest.fixture
def make_env():
    made = []

    def make(name: str = "RealUR5eDemo"):
        env = make_real_env(name, FAST)
        made.append(env)
        return env

    yield make
    for env in made:
        env.close()


def record_with_fault(env, tmp_path, inject, expected, match):
    """Record until ``inject(twin, env)`` at step FAULT_AT raises ``expected``; the arm is
    left stopped and the episode out. Returns the ``pytest.raises`` info."""
    from rmb_lerobot.envs.real.record import record_episode

    twin = env.sim.device.twins[0]
    count = iter(range(1000))

    def policy(obs):
        k = next(count)
        if k == FAULT_AT:
            return inject(twin, env)
        return env.home_command + np.r_[0.05 * np.sin(0.3 * k), np.zeros(len(env.home_command) - 1)]

    path = tmp_path / "episode.rmb"
    with pytest.raises(expected, match=match) as error:
        record_episode(env, policy, path, steps=30)
    assert not path.exists() and list(tmp_path.iterdir()) == []  # left out, nothing half written
    assert twin.sim.wait(twin.sim.at_rest, BOUND_S)  # the arm is stopped
    return error


def fault(hook):
    def inject(twin, env):
        hook(twin)
        return env.home_command

    return inject


def test_connection_lost_mid_episode(make_env, tmp_path):
    record_with_fault(
        make_env(),
        tmp_path,
        fault(lambda t: t.drop_connection()),
        ConnectionLost,
        "connection lost",
    )


def test_sdk_error_code(make_env, tmp_path):
    inject = fault(lambda t: t.fail_next("set_servo_angle", 11))
    error = record_with_fault(make_env("RealXarm7Demo"), tmp_path, inject, SdkError, "code 11")
    assert error.value.code == 11


def test_protective_stop(make_env, tmp_path):
    env = make_env()
    inject = fault(lambda t: t.protective_stop())
    record_with_fault(env, tmp_path, inject, ProtectiveStop, "PROTECTIVE_STOP")
    assert env.sim.device.twins[0].sim.stop_reason is not None


def test_gripper_fault(make_env, tmp_path):
    record_with_fault(
        make_env(), tmp_path, fault(lambda t: t.gripper_fault()), GripperFault, "fault"
    )


def test_stale_state(make_env, tmp_path):
    record_with_fault(
        make_env(),
        tmp_path,
        fault(lambda t: t.freeze_timestamps()),
        DriverStale,
        "stale|not advanced",
    )


def test_a_policy_emitting_nan(make_env, tmp_path):
    def nan(twin, env):
        return np.full(env.home_command.shape, np.nan)

    # The action mode refuses it before the safety layer would (NonFiniteCommand).
    refused = (ValueError, NonFiniteCommand)
    record_with_fault(make_env(), tmp_path, nan, refused, "non-finite|not finite")


def test_ctrl_c_during_a_reset_move(make_env, tmp_path, python_sigint):
    env = make_env()
    env.reset(seed=0)
    twin = env.sim.device.twins[0]
    away = env.home_command.copy()
    away[0] += 1.5  # 1.5 rad at RMB's UR5e reset scale: a move of about 1.5 s
    env.unwrapped.home_command = away
    env.sim.options = dataclasses.replace(env.sim.options, reset_scale=0.3)
    timer = threading.Timer(0.3, _thread.interrupt_main)
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        env.reset(seed=0)
    timer.join()
    assert twin.sim.wait(twin.sim.at_rest, BOUND_S)
    assert abs(twin.sim.read().joint_pos[0] - away[0]) > 0.3  # stopped on the way
