"""GELLO through the real dynamixel-sdk, talking to a fake servo chain on a pty.

The device is used as the teleop loop uses it: ``connect``, ``is_ready(measured joints)``
in standby, then ``read()`` per step. The servos are moved with
``FakeDynamixelChain.set_positions`` (raw counts), as a hand moves the leader arm.
"""

from __future__ import annotations

import itertools
import math
import sys

import numpy as np
import pytest

pytest.importorskip("dynamixel_sdk", reason="extra gello (in `make setup`'s EXTRAS)")

from rmb_lerobot.envs.teleop.device import JointTarget
from rmb_lerobot.envs.teleop.fakes.dynamixel import (
    FakeDynamixelChain,
    crc16,
    stuff,
    unstuff,
)
from rmb_lerobot.envs.teleop.gello import (
    GelloArmConfig,
    GelloConfig,
    GelloDevice,
    aligned_offsets,
    load_rmb_gello_yaml,
    raw_to_rad,
)

# RMB's UR5e GELLO (Gello_RealUR5eDual.yaml style): offsets multiples of π/2, one sign -1.
OFFSETS = (math.pi, 1.5 * math.pi, math.pi, -0.5 * math.pi, math.pi, 2 * math.pi)
SIGNS = (1, 1, -1, 1, 1, 1)
GRIPPER = (7, 202.04, 160.24)
UR5E_HOME = np.array([math.pi, -math.pi / 2, -1.72788, -1.41372, math.pi / 2, math.pi / 2])


def raw_for(q: np.ndarray, offsets=OFFSETS, signs=SIGNS) -> dict[int, int]:
    """Raw counts that make the arm joints read ``q`` (to one count)."""
    rad = np.asarray(q) * np.asarray(signs) + np.asarray(offsets)
    return {i + 1: round(r / math.pi * 2048) for i, r in enumerate(rad)}


def gripper_raw(deg: float) -> dict[int, int]:
    return {GRIPPER[0]: round(math.radians(deg) / math.pi * 2048)}


def expected_q(raw: dict[int, int], offsets=OFFSETS, signs=SIGNS) -> np.ndarray:
    rad = np.array([raw[i + 1] / 2048 * math.pi for i in range(len(offsets))])
    return (rad - np.asarray(offsets)) * np.asarray(signs)


def arm(chain: FakeDynamixelChain, gripper=GRIPPER) -> GelloArmConfig:
    return GelloArmConfig(
        port=chain.path, joint_ids=(1, 2, 3, 4, 5, 6), joint_offsets=OFFSETS,
        joint_signs=SIGNS, gripper=gripper,
    )  # fmt: skip


@pytest.fixture
def chain():
    with FakeDynamixelChain({**raw_for(UR5E_HOME), **gripper_raw(GRIPPER[1])}) as servos:
        yield servos


def test_fake_chain_speaks_the_sdks_protocol():
    import dynamixel_sdk as sdk

    handler = sdk.PacketHandler(2.0)
    for data in (bytes(range(40)), b"\xff\xff\xfd\x00\x01\x07\x00\x02\x84\x00\x04\x00"):
        assert crc16(data) == handler.updateCRC(0, list(data), len(data))
    body = b"\x55\x00\xff\xff\xfd\x00\xff\xff\xfd"
    assert stuff(body) == b"\x55\x00\xff\xff\xfd\xfd\x00\xff\xff\xfd\xfd"
    assert unstuff(stuff(body)) == body
    # A position whose bytes are FF FF FD (stuffed on the wire) and a negative one.
    with FakeDynamixelChain({1: 0x00FDFFFF, 2: -4096}) as servos:
        port = sdk.PortHandler(servos.path)
        assert port.openPort() and port.setBaudRate(57600)
        reader = sdk.GroupSyncRead(port, handler, 132, 4)
        assert reader.addParam(1) and reader.addParam(2)
        assert reader.txRxPacket() == sdk.COMM_SUCCESS
        assert reader.getData(1, 132, 4) == 0x00FDFFFF
        assert raw_to_rad(reader.getData(2, 132, 4)) == pytest.approx(-2 * math.pi)
        assert handler.ping(port, 9)[1] == sdk.COMM_RX_TIMEOUT  # nobody at ID 9
        port.closePort()


def test_joints_are_raw_minus_offset_times_sign_and_gripper_maps_to_0_1(chain):
    config = GelloConfig(arms=(arm(chain),), smoothing=1.0)
    rng = np.random.default_rng(0)
    with GelloDevice(config) as gello:
        for deg, closure in ((202.04, 0.0), (160.24, 1.0), (181.14, 0.5), (230, 0.0), (100, 1.0)):
            q = UR5E_HOME + rng.uniform(-1.0, 1.0, 6)
            raw = raw_for(q)
            chain.set_positions({**raw, **gripper_raw(deg)})
            target = gello.read().arms[0]
            assert isinstance(target, JointTarget)
            np.testing.assert_allclose(target.joints, expected_q(raw), atol=1e-12)
            np.testing.assert_allclose(target.joints, q, atol=2 * math.pi / 4096)
            assert target.gripper == pytest.approx(closure, abs=2e-3)
    assert chain.received[0x82] >= 5  # one GroupSyncRead per read()


def test_offsets_shift_by_whole_turns_to_read_nearest_the_robot(chain):
    # The servos are multi-turn: the leader may sit whole turns away from its calibration.
    for seed in range(4):
        rng = np.random.default_rng(seed)
        turns = rng.integers(-2, 3, 6)
        q_device = UR5E_HOME + rng.uniform(-0.3, 0.3, 6)
        raw = raw_for(q_device + 2 * math.pi * turns)
        chain.set_positions(raw)
        with GelloDevice(GelloConfig(arms=(arm(chain),), smoothing=1.0)) as gello:
            np.testing.assert_allclose(gello.read().arms[0].joints, expected_q(raw), atol=1e-12)
            gello.align([UR5E_HOME])
            joints = gello.read().arms[0].joints
        np.testing.assert_allclose(joints, q_device, atol=2 * math.pi / 4096)
        assert np.all(np.abs(joints - UR5E_HOME) <= math.pi)
    # The rule itself, for both signs: the result is within π of the start.
    for sign in (1.0, -1.0):
        offsets = aligned_offsets(np.array([7.0]), np.array([0.5]), np.array([sign]), np.zeros(1))
        assert abs((7.0 - offsets[0]) * sign) <= math.pi


def test_ready_only_within_30_degrees_then_a_50_step_blend_into_the_device(chain):
    robot = UR5E_HOME.copy()
    device_pose = UR5E_HOME + np.radians([31, 0, 0, 0, 0, 0])
    chain.set_positions(raw_for(device_pose))
    config = GelloConfig(arms=(arm(chain),), start_joints=(tuple(robot),), smoothing=1.0)
    with GelloDevice(config) as gello:
        assert not gello.is_ready([robot])
        assert "arm 0 joint 0: 31 deg" in gello.not_ready_reason
        device_pose = UR5E_HOME + np.radians([29, -20, 10, 0, 5, -29])
        raw = raw_for(device_pose)
        chain.set_positions(raw)
        assert gello.is_ready([robot]) and gello.not_ready_reason == ""
        target = expected_q(raw)
        commands = [gello.read().arms[0].joints for _ in range(55)]
    # RMB's blend: c <- r q + (1 - r) c with r = k / 50, from the robot's joints.
    np.testing.assert_allclose(commands[0], robot)
    c = robot.copy()
    for k, command in enumerate(commands[:50]):
        c = (k / 50) * target + (1 - k / 50) * c
        np.testing.assert_allclose(command, c, atol=1e-12)
    gaps = [np.max(np.abs(command - target)) for command in commands]
    assert all(b <= a + 1e-12 for a, b in itertools.pairwise(gaps))  # never overshoots
    for command in commands[50:]:
        np.testing.assert_allclose(command, target, atol=1e-12)


def test_smoothing_weights_a_new_reading_099_as_gello_does(chain):
    with GelloDevice(GelloConfig(arms=(arm(chain),))) as gello:
        first = gello.read().arms[0].joints
        moved = raw_for(UR5E_HOME + 0.1)
        chain.set_positions(moved)
        second = gello.read().arms[0].joints
    np.testing.assert_allclose(second, 0.01 * first + 0.99 * expected_q(moved), atol=1e-12)


def test_two_arms_on_two_ports_give_one_target_each():
    left_q, right_q = UR5E_HOME, UR5E_HOME + 0.2
    with (
        FakeDynamixelChain(raw_for(left_q)) as left,
        FakeDynamixelChain(raw_for(right_q)) as right,
    ):
        config = GelloConfig(arms=(arm(left, None), arm(right, None)), smoothing=1.0)
        with GelloDevice(config) as gello:
            assert gello.is_ready([left_q, right_q])
            for _ in range(51):
                reading = gello.read()
    assert set(reading.arms) == {0, 1}
    np.testing.assert_allclose(reading.arms[0].joints, left_q, atol=2e-3)
    np.testing.assert_allclose(reading.arms[1].joints, right_q, atol=2e-3)
    assert reading.arms[0].gripper == 0.0  # no gripper servo: open


def test_errors_name_the_port_the_silent_servo_and_the_extra(chain, monkeypatch, tmp_path):
    silent = GelloArmConfig(chain.path, (1, 2, 3, 4, 5, 6), OFFSETS, SIGNS, (8, 200.0, 160.0))
    with pytest.raises(ConnectionError, match=r"servo IDs \[8\] on " + chain.path):
        GelloDevice(GelloConfig(arms=(silent,))).connect()
    missing = GelloArmConfig(str(tmp_path / "ttyUSB9"), (1,), (0.0,), (1,))
    with pytest.raises(ConnectionError, match="ttyUSB9"):
        GelloDevice(GelloConfig(arms=(missing,))).connect()
    with pytest.raises(ValueError, match="joint_signs must be 1 or -1"):
        GelloArmConfig(chain.path, (1, 2), (0.0, 0.0), (1, 2))
    with pytest.raises(ValueError, match="2 joint_ids but 1 joint_offsets"):
        GelloArmConfig(chain.path, (1, 2), (0.0,), (1, 1))
    with pytest.raises(RuntimeError, match="not connected"):
        GelloDevice(GelloConfig(arms=(arm(chain),))).read()
    monkeypatch.setitem(sys.modules, "dynamixel_sdk", None)
    with pytest.raises(ImportError, match=r"lerobot_env_rmb\[gello\]"):
        GelloDevice(GelloConfig(arms=(arm(chain),))).connect()


def test_reads_rmbs_gello_yaml(tmp_path):
    path = tmp_path / "Gello_RealUR5eDual.yaml"
    path.write_text(
        "0:\n  port: /dev/ttyUSB0\n  config:\n    joint_ids: [1, 2, 3, 4, 5, 6]\n"
        "    joint_signs: [1, 1, -1, 1, 1, 1]\n"
        "    joint_offsets: [3.14159, 4.71239, 3.14159, -1.5708, 3.14159, 6.28319]\n"
        "    gripper_config: [7, 202.04, 160.24]\n"
        "1:\n  port: /dev/ttyUSB1\n  config:\n    joint_ids: [1, 2, 3, 4, 5, 6]\n"
        "    joint_signs: [1, 1, 1, 1, 1, 1]\n    joint_offsets: [0, 0, 0, 0, 0, 0]\n"
    )
    config = load_rmb_gello_yaml(path)
    assert [a.port for a in config.arms] == ["/dev/ttyUSB0", "/dev/ttyUSB1"]
    assert config.arms[0].joint_signs == SIGNS and config.arms[0].gripper == GRIPPER
    assert config.arms[1].gripper is None and config.arms[0].servo_ids == (1, 2, 3, 4, 5, 6, 7)
    bad = tmp_path / "bad.yaml"
    bad.write_text("0:\n  port: /dev/ttyUSB0\n")
    with pytest.raises(ValueError, match=r"bad.yaml: arm 0 needs port and config"):
        load_rmb_gello_yaml(bad)
