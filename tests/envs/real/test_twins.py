"""The twins themselves: wall-clock stepping, the controller's own protective stops, the SDK
return conventions they copy, and that importing the package never imports a hardware SDK."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import mujoco
import numpy as np
import pytest

from rmb_lerobot.envs.real.testing import wait_for
from rmb_lerobot.envs.real.twins.sim import ArmSim, Box
from rmb_lerobot.envs.real.twins.ur5e import UR5eTwin
from rmb_lerobot.envs.real.twins.xarm7 import XArm7Twin
from rmb_lerobot.envs.robots import UR5E, XARM7

HOST = "127.0.0.1"


@pytest.fixture(scope="module")
def ur5e_twin():
    twin = UR5eTwin(HOST)
    yield twin
    twin.close()


@pytest.fixture(scope="module")
def xarm7_twin():
    twin = XArm7Twin(HOST)
    yield twin
    twin.close()


def test_simulated_time_follows_the_wall_clock(ur5e_twin):
    sim = ur5e_twin.sim
    start_sim, start_wall = sim.read().time, time.monotonic()
    time.sleep(1.0)
    advanced, wall = sim.read().time - start_sim, time.monotonic() - start_wall
    # Never ahead of the clock (it may catch up on a lag of at most 0.1 s it had at the start);
    # behind only when this loaded machine starves the thread.
    assert 0.2 < advanced <= wall + 0.1 + 0.01


def test_collision_stops_the_arm(ur5e_twin):
    home = np.array(UR5E.arms[0].home)
    goal = home + np.array([0.0, -0.35, 0.0, 0.0, 0.0, 0.0])  # lowers the gripper 17 cm
    model = ur5e_twin.sim.model
    data = mujoco.MjData(model)
    ur5e_twin.sim.arm.set_home(model, data)
    for name, q in zip(UR5E.arms[0].joints, goal, strict=True):
        data.joint(name).qpos[0] = q
    mujoco.mj_kinematics(model, data)
    in_the_way = tuple(float(v) for v in data.site(UR5E.arms[0].tcp_frame).xpos)
    sim = ArmSim(UR5E, obstacles=[Box(in_the_way, (0.04, 0.04, 0.04))])
    try:
        time.sleep(0.2)
        assert sim.stop_reason is None  # nothing touches at home
        assert sim.move_to(goal, 2.0)
        assert wait_for(lambda: sim.stop_reason is not None)
        assert sim.stop_reason.startswith("collision") and "twin_box" in sim.stop_reason
        assert wait_for(sim.at_rest)
        assert np.abs(sim.read().joint_pos - goal).max() > 0.05  # stopped short of the box
        assert not sim.move_to(home, 1.0)  # refused until the stop is released
        sim.clear_stop()
        assert sim.move_to(home, 1.0)
    finally:
        sim.close()


def test_ur5e_twin_rtde_conventions(ur5e_twin):
    ur5e_twin.reset()
    control = ur5e_twin.RTDEControlInterface(HOST)
    receive = ur5e_twin.RTDEReceiveInterface(HOST)
    assert control.isConnected() and receive.isConnected()
    first = receive.getTimestamp()
    assert wait_for(lambda: receive.getTimestamp() > first)
    assert len(receive.getActualQ()) == 6 and receive.getSafetyMode() == 1
    assert control.servoJ(receive.getActualQ(), 0.5, 0.5, 0.1, 0.2, 100) is True
    ur5e_twin.drop_connection()
    assert not receive.isConnected()
    frozen = receive.getTimestamp()
    time.sleep(0.05)
    assert receive.getTimestamp() == frozen  # ur-rtde keeps returning the last values
    with pytest.raises(RuntimeError, match="not connected"):
        control.servoJ(receive.getActualQ(), 0.5, 0.5, 0.1, 0.2, 100)
    with pytest.raises(RuntimeError, match=r"Could not connect to: 127\.0\.0\.1 at 30004"):
        ur5e_twin.RTDEReceiveInterface(HOST)
    ur5e_twin.reset()


def test_xarm7_twin_sdk_codes(xarm7_twin):
    xarm7_twin.reset()
    arm = xarm7_twin.XArmAPI(HOST)
    assert arm.connected and arm.state == 4
    q = list(XARM7.arms[0].home)
    assert arm.set_servo_angle(angle=q, is_radian=True) == 9  # not ready: state 4
    assert arm.motion_enable(True) == 0 and arm.set_mode(6) == 0 and arm.set_state(0) == 0
    code, (position, _velocity, _effort) = arm.get_joint_states(is_radian=False)
    assert code == 0 and position[3] == pytest.approx(np.degrees(0.8), abs=1.0)
    beyond = [*q[:3], 4.5, *q[4:]]
    assert arm.set_servo_angle(angle=beyond, is_radian=True) == -8
    degrees = list(np.degrees(q) + 3.0)
    assert arm.set_servo_angle(angle=degrees, speed=30, mvtime=0.3, is_radian=False) == 0
    assert wait_for(lambda: abs(arm.get_joint_states(is_radian=False)[1][0][0] - 3.0) < 0.5)
    xarm7_twin.protective_stop()
    assert arm.error_code == 31 and arm.state == 4
    assert arm.get_joint_states(is_radian=True)[0] == 0  # getters answer while in error
    assert arm.set_servo_angle(angle=q, is_radian=True) == 1
    arm.disconnect()
    assert arm.set_servo_angle(angle=q, is_radian=True) == -1
    assert arm.get_joint_states(is_radian=True)[0] == -1
    xarm7_twin.reset()


def test_twins_run_on_loopback_only():
    with pytest.raises(ValueError, match="loopback"):
        UR5eTwin("robot.invalid")
    with pytest.raises(ValueError, match="loopback"):
        XArm7Twin("robot.invalid")


def test_importing_the_package_imports_no_sdk(tmp_path: Path):
    """With poisoned SDK modules first on the path, the package and its drivers import."""
    for module in ("rtde_control", "rtde_receive", "pyrealsense2"):
        (tmp_path / f"{module}.py").write_text(f"raise RuntimeError('{module} was imported')\n")
    (tmp_path / "xarm").mkdir()
    (tmp_path / "xarm" / "__init__.py").write_text("raise RuntimeError('xarm was imported')\n")
    code = (
        "import rmb_lerobot, rmb_lerobot.envs.real.drivers.ur5e, "
        "rmb_lerobot.envs.real.drivers.xarm7, sys; "
        "bad = {'rtde_control', 'rtde_receive', 'xarm', 'pyrealsense2'} & set(sys.modules); "
        "assert not bad, bad; print('ok')"
    )
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp_path), *sys.path])}
    done = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=240
    )
    assert done.returncode == 0 and done.stdout.strip() == "ok", done.stderr[-2000:]


def test_xarm_twin_signatures_match_the_sdk():
    """Where xarm-python-sdk is installed: every call the driver makes binds to the SDK's
    ``XArmAPI`` and to the twin alike (run on a lab machine with the ``xarm7`` extra)."""
    wrapper = pytest.importorskip("xarm.wrapper")
    import inspect

    from rmb_lerobot.envs.real.twins.xarm7 import XArmAPITwin

    arm = wrapper.XArmAPI(HOST, do_not_open=True)
    calls = {
        "motion_enable": ((True,), {}),
        "ft_sensor_enable": ((1,), {}),
        "ft_sensor_set_zero": ((), {}),
        "clean_error": ((), {}),
        "set_mode": ((6,), {}),
        "set_state": ((0,), {}),
        "set_collision_sensitivity": ((1,), {}),
        "clean_gripper_error": ((), {}),
        "set_gripper_mode": ((0,), {}),
        "set_gripper_enable": ((True,), {}),
        "get_joint_states": ((), {"is_radian": True}),
        "set_servo_angle": (
            (),
            {"angle": [0.0] * 7, "speed": 1.0, "mvtime": 0.1, "is_radian": True, "wait": False},
        ),
        "set_gripper_position": ((800.0,), {"wait": False}),
        "get_gripper_position": ((), {}),
        "get_gripper_err_code": ((), {}),
        "get_ft_sensor_data": ((), {}),
    }
    for name, (args, kwargs) in calls.items():
        inspect.signature(getattr(arm, name)).bind(*args, **kwargs)
        inspect.signature(getattr(XArmAPITwin, name)).bind(None, *args, **kwargs)
