"""XArm7Driver against the xArm7 twin (xarm-python-sdk's XArmAPI calls and return codes).

Every non-zero return code is an SdkError naming the call and the code, and where the code
says more also the matching DriverError subclass. Faults leave the twin's arm at rest. Waits
poll with generous bounds and assert physical outcomes, never timing.
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
    GripperFault,
    ProtectiveStop,
    SdkError,
    StaleState,
)
from rmb_lerobot.envs.real.drivers.gripper_units import (
    xarm_gripper_command_to_pulse,
    xarm_gripper_pulse_to_command,
)
from rmb_lerobot.envs.real.drivers.xarm7 import XArm7Config, XArm7Driver
from rmb_lerobot.envs.real.testing import wait_for
from rmb_lerobot.envs.real.twins.xarm7 import XArm7Twin
from rmb_lerobot.envs.robots import XARM7

HOST = "127.0.0.1"
HOME = np.array(XARM7.arms[0].home)
BOUND_S = 15.0


def config(**kwargs) -> XArm7Config:
    return XArm7Config(host=HOST, driver="sim", settle_s=0.01, **kwargs)


@pytest.fixture(scope="module")
def twin():
    twin = XArm7Twin(HOST)
    yield twin
    twin.close()


@pytest.fixture
def driver(twin):
    twin.reset()
    driver = XArm7Driver(config(), twin=twin)
    driver.connect()
    yield driver
    driver.close()


def at_rest(twin: XArm7Twin) -> bool:
    return wait_for(twin.sim.at_rest)


def start_far_move(driver: XArm7Driver) -> np.ndarray:
    goal = HOME + np.array([0.6, 0, 0, 0, 0, 0, 0])
    driver.command_joints(goal, 10.0)
    assert wait_for(lambda: np.abs(driver.read().joint_vel).max() > 0.01)
    return goal


def test_gripper_units_map_open_to_840_and_closed_to_0():
    assert xarm_gripper_command_to_pulse(0.0) == pytest.approx(840.0)  # open
    assert xarm_gripper_command_to_pulse(255.0) == pytest.approx(0.0)  # closed
    for value in (0.0, 10.0, 127.5, 255.0):
        assert xarm_gripper_pulse_to_command(xarm_gripper_command_to_pulse(value)) == (
            pytest.approx(value)
        )


def test_connect_runs_rmbs_sequence(driver, twin):
    assert isinstance(driver, ArmDriver)
    assert twin.enabled and twin.mode == 6 and twin.gripper_enabled
    assert twin.error_code == 0


def test_reads_sane_state_at_home(driver):
    state = driver.read()
    assert state.joint_pos.shape == (7,) and state.joint_vel.shape == (7,)
    np.testing.assert_allclose(state.joint_pos, HOME, atol=0.02)
    assert np.abs(state.joint_vel).max() < 0.05
    assert 0 <= state.gripper < 10  # open
    assert state.wrench is not None and np.abs(state.wrench).max() < 1.0  # zeroed at connect
    assert wait_for(lambda: driver.read().timestamp > state.timestamp)


def test_small_joint_move_arrives(driver, twin):
    goal = HOME + np.array([0.1, -0.1, 0.1, 0.1, -0.05, 0.1, 0.1])
    driver.command_joints(goal, 0.5)
    assert wait_for(lambda: np.abs(driver.read().joint_pos - goal).max() < 0.01)
    np.testing.assert_allclose(twin.sim.read().joint_pos, goal, atol=0.01)


def test_gripper_closes_and_opens(driver, twin):
    driver.command_gripper(255)
    assert wait_for(lambda: driver.read().gripper > 200)
    assert twin.sim.read().gripper > 200
    driver.command_gripper(0)
    assert wait_for(lambda: driver.read().gripper < 30)


def test_zero_wrench_and_its_error_code(driver, twin):
    driver.zero_wrench()
    assert np.abs(driver.read().wrench).max() < 0.5
    twin.fail_next("set_ft_sensor_zero", 12)
    with pytest.raises(SdkError, match=r"ft_sensor_set_zero returned code 12") as caught:
        driver.zero_wrench()
    assert caught.value.code == 12


@pytest.mark.parametrize(
    "call", ["motion_enable", "set_ft_sensor_enable", "set_mode", "set_state", "set_gripper_enable"]
)
def test_every_connect_call_is_checked(twin, call):
    twin.reset()
    twin.fail_next(call, 10)
    driver = XArm7Driver(config(), twin=twin)
    with pytest.raises(SdkError, match=r"returned code 10") as caught:
        driver.connect()
    assert caught.value.code == 10
    driver.close()


def test_sdk_error_code_on_a_command(driver, twin):
    twin.fail_next("set_servo_angle", 10)
    with pytest.raises(SdkError, match=r"xArm7 at 127\.0\.0\.1: set_servo_angle returned code 10"):
        driver.command_joints(HOME, 0.1)


def test_out_of_range_target_is_the_sdks_code(driver):
    beyond = HOME.copy()
    beyond[3] = 4.5  # joint 4: -11..225 deg
    with pytest.raises(SdkError, match=r"returned code -8 \(out of range") as caught:
        driver.command_joints(beyond, 1.0)
    assert caught.value.code == -8


def test_connection_lost_mid_episode(driver, twin):
    start_far_move(driver)
    twin.drop_connection()
    with pytest.raises(ConnectionLost, match=r"xArm7 at 127\.0\.0\.1: connection lost"):
        driver.read()
    with pytest.raises(ConnectionLost, match=r"returned code -1 \(not connected\)") as caught:
        driver.command_joints(HOME, 1.0)
    assert isinstance(caught.value, SdkError)
    assert at_rest(twin)
    driver.close()
    driver.close()


def test_protective_stop_mid_move(driver, twin):
    goal = start_far_move(driver)
    twin.protective_stop()
    with pytest.raises(ProtectiveStop, match=r"controller error 31 \(collision") as caught:
        driver.read()
    assert isinstance(caught.value, SdkError) and caught.value.code == 31
    with pytest.raises(ProtectiveStop, match="set_servo_angle returned code 1"):
        driver.command_joints(goal, 1.0)
    assert at_rest(twin)
    assert np.abs(twin.sim.read().joint_pos - goal).max() > 0.1


def test_gripper_fault(driver, twin):
    twin.gripper_fault(8)
    with pytest.raises(GripperFault, match=r"code 102.*gripper error 8") as caught:
        driver.command_gripper(255)
    assert isinstance(caught.value, SdkError) and caught.value.code == 102


def test_stale_state(driver, twin):
    twin.freeze()
    with pytest.raises(StaleState, match=r"returned code 3.*stale state") as caught:
        driver.read()
    assert isinstance(caught.value, SdkError)


def test_ctrl_c_during_a_move_stops_the_arm(twin, python_sigint):
    twin.reset()
    goal = HOME + np.array([0.8, 0, 0, 0, 0, 0, 0])
    timer = threading.Timer(0.5, _thread.interrupt_main)
    with pytest.raises(KeyboardInterrupt), XArm7Driver(config(), twin=twin) as driver:
        timer.start()
        deadline = time.monotonic() + BOUND_S
        while time.monotonic() < deadline:
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
    small = twin.sim.read().joint_pos + 0.05
    driver.command_joints(small, 0.3)  # ready again after a stop (mode 6, state 0)
    assert wait_for(lambda: np.abs(driver.read().joint_pos - small).max() < 0.01)
    driver.close()
    driver.close()
    assert at_rest(twin)


def test_config_needs_an_address_and_loopback_for_sim():
    with pytest.raises(TypeError):
        XArm7Config()  # type: ignore[call-arg]  # no default address
    with pytest.raises(ValueError, match="loopback"):
        XArm7Driver(XArm7Config(host="robot.invalid", driver="sim"))


def test_missing_sdk_names_the_extra():
    if importlib.util.find_spec("xarm") is not None:
        pytest.skip("xarm-python-sdk is installed")
    driver = XArm7Driver(XArm7Config(host=HOST, driver="sdk"))
    with pytest.raises(ImportError, match=r"pip install 'rmb_lerobot\[xarm7\]'"):
        driver.connect()
