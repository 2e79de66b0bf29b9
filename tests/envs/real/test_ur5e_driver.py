"""UR5eDriver against the UR5e twin (ur-rtde's calls and the Robotiq URCap socket on loopback).

Each fault a real arm can show (connection lost mid-episode, a command refused, protective
stop, gripper fault, stale state, Ctrl-C) surfaces as its DriverError subclass naming what
happened, and leaves the twin's arm at rest. Waits poll with generous bounds and assert
physical outcomes, never timing: this machine is slow and shared.
"""

from __future__ import annotations

import _thread
import importlib.util
import threading
import time

import numpy as np
import pytest

from rmb_lerobot.envs.real.driver import (
    ArmDriver,
    ConnectionLost,
    DriverError,
    GripperFault,
    ProtectiveStop,
    SdkError,
    StaleState,
)
from rmb_lerobot.envs.real.drivers.ur5e import UR5eConfig, UR5eDriver
from rmb_lerobot.envs.real.testing import wait_for
from rmb_lerobot.envs.real.twins.ur5e import UR5eTwin
from rmb_lerobot.envs.robots import UR5E

HOST = "127.0.0.1"
HOME = np.array(UR5E.arms[0].home)
BOUND_S = 15.0  # generous: the machine is loaded


@pytest.fixture(scope="module")
def twin():
    twin = UR5eTwin(HOST)
    yield twin
    twin.close()


@pytest.fixture
def driver(twin):
    twin.reset()
    driver = UR5eDriver(UR5eConfig(host=HOST, driver="sim", stale_after_s=0.3), twin=twin)
    driver.connect()
    yield driver
    driver.close()


def at_rest(twin: UR5eTwin) -> bool:
    return wait_for(twin.sim.at_rest)


def start_far_move(driver: UR5eDriver) -> np.ndarray:
    """A slow 0.6 rad move of the shoulder (10 s), so the arm is mid-move for the test."""
    goal = HOME + np.array([0.6, 0, 0, 0, 0, 0])
    driver.command_joints(goal, 10.0)
    assert wait_for(lambda: np.abs(driver.read().joint_vel).max() > 0.01)
    return goal


def test_is_an_arm_driver(driver):
    assert isinstance(driver, ArmDriver)


def test_reads_sane_state_at_home(driver):
    first = driver.read()
    assert first.joint_pos.shape == (6,) and first.joint_vel.shape == (6,)
    np.testing.assert_allclose(first.joint_pos, HOME, atol=0.02)
    assert np.abs(first.joint_vel).max() < 0.05
    assert 0 <= first.gripper < 10  # open
    assert first.wrench is not None and first.wrench.shape == (6,)
    assert np.all(np.isfinite(first.wrench))
    assert wait_for(lambda: driver.read().timestamp > first.timestamp)


def test_small_joint_move_arrives(driver, twin):
    goal = HOME + np.array([0.1, -0.1, 0.1, 0.05, -0.05, 0.1])
    driver.command_joints(goal, 0.5)
    assert wait_for(lambda: np.abs(driver.read().joint_pos - goal).max() < 0.01)
    np.testing.assert_allclose(twin.sim.read().joint_pos, goal, atol=0.01)


def test_streamed_commands_arrive(driver):
    goal = HOME + np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.3])
    for s in np.linspace(0.0, 1.0, 26)[1:]:
        driver.command_joints(HOME + s * (goal - HOME), 0.02)
        time.sleep(0.02)
    assert wait_for(lambda: np.abs(driver.read().joint_pos - goal).max() < 0.01)


def test_gripper_closes_and_opens(driver, twin):
    driver.command_gripper(255)
    assert wait_for(lambda: driver.read().gripper > 200)
    assert twin.sim.read().gripper > 200
    driver.command_gripper(0)
    assert wait_for(lambda: driver.read().gripper < 30)
    with pytest.raises(ValueError, match=r"0\.\.255"):
        driver.command_gripper(300)


def test_zero_wrench(driver):
    assert abs(driver.read().wrench[2]) > 1.0  # the gripper's weight on the sensor
    driver.zero_wrench()
    assert np.abs(driver.read().wrench).max() < 0.5


def test_zero_wrench_refused_is_an_error(driver, twin):
    twin.fail_next("zeroFtSensor")
    with pytest.raises(DriverError, match="zeroFtSensor returned False"):
        driver.zero_wrench()


def test_connection_lost_mid_episode(driver, twin):
    start_far_move(driver)
    twin.drop_connection()
    with pytest.raises(ConnectionLost, match=r"UR5e at 127\.0\.0\.1.*connection lost"):
        driver.read()
    with pytest.raises(ConnectionLost, match=r"UR5e at 127\.0\.0\.1"):
        driver.command_joints(HOME, 1.0)
    assert at_rest(twin)
    driver.close()
    driver.close()
    assert at_rest(twin)


def test_refused_servoj_is_a_driver_error(driver, twin):
    twin.fail_next("servoJ")
    with pytest.raises(DriverError, match="servoJ returned False") as caught:
        driver.command_joints(HOME, 0.1)
    assert not isinstance(caught.value, (ProtectiveStop, ConnectionLost, SdkError))


def test_protective_stop_mid_move(driver, twin):
    goal = start_far_move(driver)
    twin.protective_stop()
    with pytest.raises(ProtectiveStop, match="PROTECTIVE_STOP"):
        driver.read()
    with pytest.raises(ProtectiveStop, match=r"UR5e at 127\.0\.0\.1"):
        driver.command_joints(goal, 1.0)
    assert at_rest(twin)
    assert np.abs(twin.sim.read().joint_pos - goal).max() > 0.1  # stopped short


def test_joint_limit_target_stops_the_arm(driver, twin):
    beyond = HOME.copy()
    beyond[2] = 3.3  # the elbow's range is +-pi
    with pytest.raises(ProtectiveStop, match="safety mode 3"):
        driver.command_joints(beyond, 1.0)
    assert "joint limit" in twin.sim.stop_reason
    assert at_rest(twin)


def test_gripper_fault(driver, twin):
    twin.gripper_fault(0x0E)
    with pytest.raises(GripperFault, match=r"127\.0\.0\.1:\d+.*0x0E \(overcurrent"):
        driver.read()


def test_stale_timestamps(driver, twin):
    driver.read()
    twin.freeze_timestamps()
    with pytest.raises(StaleState, match="stale state"):
        deadline = time.monotonic() + BOUND_S
        while time.monotonic() < deadline:
            driver.read()
            time.sleep(0.02)
    assert isinstance(StaleState("x"), ConnectionLost)


def test_ctrl_c_during_a_move_stops_the_arm(twin, python_sigint):
    twin.reset()
    goal = HOME + np.array([0.8, 0, 0, 0, 0, 0])
    timer = threading.Timer(0.5, _thread.interrupt_main)
    config = UR5eConfig(host=HOST, driver="sim")
    with pytest.raises(KeyboardInterrupt), UR5eDriver(config, twin=twin) as driver:
        timer.start()
        deadline = time.monotonic() + BOUND_S
        while time.monotonic() < deadline:  # a 50 Hz stream towards a goal 8 s away
            now = driver.read().joint_pos
            driver.command_joints(now + np.clip(goal - now, -0.002, 0.002), 0.02)
            time.sleep(0.02)
    timer.cancel()
    assert at_rest(twin)
    assert np.abs(twin.sim.read().joint_pos - goal).max() > 0.1


def test_stop_and_close_leave_the_arm_at_rest(driver, twin):
    goal = start_far_move(driver)
    driver.stop()
    driver.stop()
    assert at_rest(twin)
    assert np.abs(twin.sim.read().joint_pos - goal).max() > 0.1
    driver.command_joints(HOME, 1.0)  # commands work again after a stop
    driver.close()
    driver.close()
    assert at_rest(twin)


def test_driver_starts_its_own_twin():
    with UR5eDriver(UR5eConfig(host=HOST)) as driver:
        assert driver.twin is not None
        np.testing.assert_allclose(driver.read().joint_pos, HOME, atol=0.02)
        twin = driver.twin
    assert driver.twin is None
    assert twin.sim._closing.is_set()


def test_config_needs_an_address_and_loopback_for_sim():
    with pytest.raises(TypeError):
        UR5eConfig()  # type: ignore[call-arg]  # no default address
    with pytest.raises(ValueError, match="loopback"):
        UR5eDriver(UR5eConfig(host="robot.invalid", driver="sim"))
    with pytest.raises(ValueError, match="driver must be one of"):
        UR5eDriver(UR5eConfig(host=HOST, driver="real"))  # type: ignore[arg-type]


def test_missing_sdk_names_the_extra():
    if importlib.util.find_spec("rtde_control") is not None:
        pytest.skip("ur-rtde is installed")
    driver = UR5eDriver(UR5eConfig(host=HOST, driver="sdk"))
    with pytest.raises(ImportError, match=r"pip install 'rmb_lerobot\[ur5e\]'"):
        driver.connect()
