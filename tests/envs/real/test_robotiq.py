"""The Robotiq URCap client against the twin's URCap server (a real TCP socket on loopback).

Proves the protocol both ways (SET -> ack, GET -> "<VAR> <int>"), the activation sequence
and its states, moves of the MuJoCo gripper, and that every failure (fault register, refused
command, bad reply, closed or silent socket, nothing listening) is a GripperFault or a
ConnectionLost naming host:port.
"""

from __future__ import annotations

import socket
import threading

import pytest

from rmb_lerobot.envs.real.driver import ConnectionLost, GripperFault
from rmb_lerobot.envs.real.drivers.robotiq import RobotiqGripper
from rmb_lerobot.envs.real.testing import wait_for
from rmb_lerobot.envs.real.twins.robotiq_server import RobotiqServer
from rmb_lerobot.envs.real.twins.sim import ArmSim
from rmb_lerobot.envs.robots import UR5E

HOST = "127.0.0.1"
BOUND_S = 15.0


@pytest.fixture(scope="module")
def sim():
    sim = ArmSim(UR5E)
    yield sim
    sim.close()


@pytest.fixture
def server(sim):
    sim.reset()
    server = RobotiqServer(sim, HOST, 0)
    yield server
    server.close()


@pytest.fixture
def gripper(server):
    gripper = RobotiqGripper(HOST, server.port, timeout_s=2.0)
    gripper.connect()
    yield gripper
    gripper.close()


def raw_exchange(port: int, lines: list[str]) -> list[str]:
    """Send lines on a plain socket and return the reply lines (the wire format itself)."""
    with socket.create_connection((HOST, port), timeout=5.0) as sock:
        replies = []
        reader = sock.makefile("r", encoding="ascii")
        for line in lines:
            sock.sendall(line.encode("ascii") + b"\n")
            replies.append(reader.readline().strip())
        return replies


def test_wire_format(server):
    assert raw_exchange(server.port, ["GET STA", "SET ACT 1", "GET ACT", "SET POS 300"]) == [
        "STA 0",
        "ack",
        "ACT 1",
        "?",
    ]


def test_activation_sequence(gripper, server):
    assert server.status == 0 and not gripper.is_active()
    gripper.activate(timeout_s=BOUND_S)
    assert gripper.get("STA") == 3 and gripper.get("ACT") == 1 and gripper.is_active()
    gripper.check_fault()
    gripper.activate()  # already active: nothing to do


def test_activation_passes_through_activating(gripper, server):
    gripper.set(ACT=1)
    assert gripper.get("STA") in (1, 3)
    assert wait_for(lambda: gripper.get("STA") == 3)


def test_moves_the_gripper(gripper, sim):
    gripper.activate(timeout_s=BOUND_S)
    gripper.move(255, 50, 10)
    assert gripper.get("PRE") == 255
    assert wait_for(lambda: gripper.position() > 200)
    assert wait_for(lambda: gripper.get("OBJ") == 3)
    assert sim.read().gripper > 200
    gripper.move(0, 50, 10)
    assert wait_for(lambda: gripper.position() < 30)
    gripper.stop()


def test_move_before_activation_is_a_fault(gripper, server):
    gripper.move(255, 50, 10)
    with pytest.raises(GripperFault, match=rf"127\.0\.0\.1:{server.port}: fault 0x07"):
        gripper.check_fault()


def test_injected_fault(gripper, server):
    gripper.activate(timeout_s=BOUND_S)
    server.inject_fault(0x0E)
    with pytest.raises(GripperFault, match=r"fault 0x0E \(overcurrent triggered\)"):
        gripper.check_fault()


def test_refused_command_is_a_gripper_fault(gripper):
    with pytest.raises(GripperFault, match=r"answered '\?' to 'SET XYZ 1'"):
        gripper.set(XYZ=1)
    with pytest.raises(ValueError, match=r"0\.\.255"):
        gripper.set(POS=256)


def test_activation_timeout_names_the_state(gripper, server, monkeypatch):
    monkeypatch.setattr(server, "_activation_s", 60.0)
    with pytest.raises(GripperFault, match=r"activation did not finish within 0\.3 s \(STA 1"):
        gripper.activate(timeout_s=0.3)


def test_dropped_connection(gripper, server):
    gripper.activate(timeout_s=BOUND_S)
    server.drop_connections()
    with pytest.raises(ConnectionLost, match=rf"127\.0\.0\.1:{server.port}"):
        gripper.position()
    assert not gripper.connected
    with pytest.raises(ConnectionLost, match="not connected"):
        gripper.position()


def test_nothing_listening():
    with socket.create_server((HOST, 0)) as placeholder:
        port = placeholder.getsockname()[1]
    gripper = RobotiqGripper(HOST, port, timeout_s=1.0)
    with pytest.raises(ConnectionLost, match=rf"127\.0\.0\.1:{port}: cannot connect"):
        gripper.connect()


def test_silent_server_times_out():
    with socket.create_server((HOST, 0)) as listener:
        accepted: list[socket.socket] = []
        thread = threading.Thread(target=lambda: accepted.append(listener.accept()[0]))
        thread.start()
        gripper = RobotiqGripper(HOST, listener.getsockname()[1], timeout_s=0.3)
        gripper.connect()
        with pytest.raises(ConnectionLost, match=r"no reply to 'GET POS' within 0\.3 s"):
            gripper.position()
        thread.join(timeout=5.0)
        for sock in accepted:
            sock.close()
