"""A teleoperation session driven by scripted keys: what it saves, and what it never leaves."""

from __future__ import annotations

import json
import os
import signal
from pathlib import Path

import numpy as np
import pytest

from rmb_lerobot import keys as K
from rmb_lerobot.cli.data import main as rmb_data
from rmb_lerobot.envs.interrupts import Interrupted, interrupts_raise
from rmb_lerobot.envs.teleop.device import DeviceReading, InputDevice, JointTarget
from rmb_lerobot.envs.teleop.keyboard import KeyboardDevice
from rmb_lerobot.envs.teleop.keys import ScriptedKeySource
from rmb_lerobot.envs.teleop.session import TeleopConfig, TeleopSession
from rmb_lerobot.episode import open_episode

# n: initial -> standby, n: -> teleop (recording starts), 3 x w, z, n: -> end, s: save.
SAVE_ONE = [(0, "n"), (1, "n"), (2, "w"), (3, "w"), (4, "w"), (5, "z"), (7, "n"), (8, "s")]
RECORDED = 6  # steps 1..6: recording starts with the step n enters teleop, ends before n


def run(env, out: Path, events, device=None, **config) -> TeleopSession:
    session = TeleopSession(
        env,
        device or KeyboardDevice(num_arms=len(env.robot.arms)),
        ScriptedKeySource(events),
        TeleopConfig(out=out, realtime=False, **config),
        log=lambda message: None,
    )
    session.run()
    return session


def everything_in(directory: Path) -> list[str]:
    """Every entry, hidden temporaries and lock files included."""
    return sorted(p.name for p in directory.iterdir())


def test_a_saved_episode_holds_every_key_and_reads_back(cable_env, tmp_path, capsys):
    session = run(cable_env, tmp_path, SAVE_ONE, world_idx=(3,), task_desc="Route it.")
    [path] = session.result.saved
    assert path.name == "MujocoUR5eCable_world3_000.rmb"
    assert everything_in(tmp_path) == [path.name]
    with open_episode(path) as ep:
        assert len(ep) == RECORDED
        assert ep.attrs["env"] == "MujocoUR5eCableEnv" and ep.attrs["world_idx"] == 3
        assert ep.attrs["task_desc"] == "Route it." and ep.attrs["demo_name"] == path.stem
        for key in (
            K.TIME,
            K.REWARD,
            K.MEASURED_JOINT_POS,
            K.COMMAND_JOINT_POS,
            K.COMMAND_JOINT_POS_REL,
            K.MEASURED_EEF_POSE,
            K.COMMAND_EEF_POSE,
            K.COMMAND_EEF_POSE_REL,
            K.MEASURED_EEF_WRENCH,
            K.COMMAND_GRIPPER_JOINT_POS,
            "front_rgb_image",
        ):
            assert key in ep, key
        # Three W presses: the eef target 3 cm along world +x (root -x: the UR5e's root frame
        # is turned by pi), then Z: the gripper command up by 50.
        pose = ep[K.COMMAND_EEF_POSE][:]
        assert pose[-1, 0] - pose[0, 0] == pytest.approx(-0.03, abs=2e-4)
        np.testing.assert_allclose(ep[K.COMMAND_GRIPPER_JOINT_POS][:, 0], [0, 0, 0, 0, 50, 50])
        assert np.all(np.diff(ep[K.TIME][:]) > 0)
    assert rmb_data(["info", str(path), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert "command_joint_pos" in json.dumps(info)


def test_a_discarded_episode_leaves_nothing(cable_env, tmp_path):
    session = run(cable_env, tmp_path, [(0, "n"), (1, "n"), (2, "w"), (3, "n"), (4, "f")])
    assert session.result.saved == [] and session.result.discarded == 1
    assert everything_in(tmp_path) == []


def test_esc_while_recording_leaves_nothing(cable_env, tmp_path):
    session = run(cable_env, tmp_path, [(0, "n"), (1, "n"), (2, "w"), (3, "esc")])
    assert session.result.discarded == 1 and everything_in(tmp_path) == []


class InterruptingKeys(ScriptedKeySource):
    """Scripted keys, then Ctrl-C (KeyboardInterrupt) at poll ``at``."""

    def __init__(self, events, at: int):
        super().__init__(events, then=())
        self.at = at

    def poll(self) -> list[str]:
        if self.polls == self.at:
            raise KeyboardInterrupt
        return super().poll()


@pytest.mark.parametrize("at", [3, 6])
def test_an_interrupted_episode_leaves_nothing(cable_env, tmp_path, at):
    """Ctrl-C while recording (poll 3) or in the end phase before saving (poll 6)."""
    keys = InterruptingKeys([(0, "n"), (1, "n"), (2, "w"), (4, "n")], at=at)
    session = TeleopSession(
        cable_env, KeyboardDevice(), keys, TeleopConfig(out=tmp_path, realtime=False)
    )
    with pytest.raises(KeyboardInterrupt):
        session.run()
    assert everything_in(tmp_path) == []


class SignallingKeys(ScriptedKeySource):
    """Scripted keys; at poll ``at`` the process sends itself SIGINT (a real Ctrl-C)."""

    def __init__(self, events, at: int):
        super().__init__(events, then=())
        self.at = at

    def poll(self) -> list[str]:
        if self.polls == self.at:
            os.kill(os.getpid(), signal.SIGINT)
        return super().poll()


def test_ctrl_c_keeps_saved_episodes_and_drops_the_one_being_recorded(cable_env, tmp_path):
    """As in rmb-teleop: SIGINT raises Interrupted at the next step boundary."""
    events = [(0, "n"), (1, "n"), (2, "w"), (3, "n"), (4, "s")]  # one saved episode
    events += [(5, "n"), (6, "n"), (7, "w")]  # the second is being recorded at poll 8
    session = TeleopSession(
        cable_env,
        KeyboardDevice(),
        SignallingKeys(events, at=8),
        TeleopConfig(out=tmp_path, realtime=False),
    )
    with interrupts_raise(), pytest.raises(Interrupted) as interrupted:
        session.run()
    assert interrupted.value.signum == signal.SIGINT
    [saved] = session.result.saved
    assert everything_in(tmp_path) == [saved.name]
    with open_episode(saved) as ep:
        assert len(ep) == 2


def test_save_success_only_discards_a_failed_episode(cable_env, tmp_path):
    session = run(cable_env, tmp_path, SAVE_ONE, save_success_only=True)
    assert not session.success  # three presses do not route a cable
    assert session.result.saved == [] and everything_in(tmp_path) == []


def test_sync_phase_drives_the_robot_unrecorded(cable_env, tmp_path):
    # n standby, n sync, w w (not recorded), n teleop (recording), n end, s save.
    events = [(0, "n"), (1, "n"), (2, "w"), (3, "w"), (4, "n"), (6, "n"), (7, "s")]
    session = run(cable_env, tmp_path, events, sync_before_record=True, world_idx=(0,))
    cable_env.reset(seed=0, options={"world_idx": 0})
    home_x = cable_env.command_eef_pose[0]
    with open_episode(session.result.saved[0]) as ep:
        assert len(ep) == 2
        # Recording starts where the sync left the robot: 2 cm along world +x.
        assert ep[K.COMMAND_EEF_POSE][0, 0] - home_x == pytest.approx(-0.02, abs=2e-4)


def test_episodes_are_numbered_and_cycle_through_the_worlds(cable_env, tmp_path):
    one = [(t, key) for t, key in SAVE_ONE if key != "z"]
    two = one + [(t + 9, key) for t, key in one]
    session = run(cable_env, tmp_path, two, world_idx=(2, 4), max_episodes=2)
    names = [p.name for p in session.result.saved]
    assert names == ["MujocoUR5eCable_world2_000.rmb", "MujocoUR5eCable_world4_001.rmb"]
    again = run(cable_env, tmp_path, one, world_idx=(1,), fmt="hdf5", demo_name="MujocoUR5eCable")
    assert again.result.saved[0].name == "MujocoUR5eCable_world1_002.hdf5"


class SlowToAlign(InputDevice):
    """A joint-space device (GELLO-like) that is ready only from its second check on."""

    name = "slow"

    def __init__(self, joints: np.ndarray):
        self.joints, self.checks = joints, 0

    def connect(self) -> None:
        pass

    def is_ready(self, measured_joints) -> bool:
        self.checks += 1
        return self.checks > 1

    def read(self) -> DeviceReading:
        return DeviceReading(arms={0: JointTarget(self.joints, gripper=0.5)})

    def close(self) -> None:
        pass


def test_standby_waits_until_the_device_is_ready(cable_env, tmp_path):
    cable_env.reset(seed=0)
    target = cable_env.command[:6] + 0.05
    device = SlowToAlign(target)
    # n standby, n (not ready yet), n teleop, n end, s save.
    events = [(0, "n"), (1, "n"), (2, "n"), (4, "n"), (5, "s")]
    session = run(cable_env, tmp_path, events, device=device)
    assert device.checks == 2
    with open_episode(session.result.saved[0]) as ep:
        assert len(ep) == 2
        np.testing.assert_allclose(ep[K.COMMAND_JOINT_POS][0], [*target, 127.5])


def test_the_loop_keeps_the_control_period(cable_env, tmp_path):
    """Pacing against a fake clock: each step sleeps what is left of the 32 ms period."""
    now = [0.0]
    sleeps: list[float] = []

    def sleep(seconds: float) -> None:
        sleeps.append(seconds)
        now[0] += seconds

    def clock() -> float:
        now[0] += 0.010  # every step "takes" 10 ms
        return now[0]

    session = TeleopSession(
        cable_env,
        KeyboardDevice(),
        ScriptedKeySource([(4, "esc")], then=()),
        TeleopConfig(out=tmp_path, realtime=True),
        clock=clock,
        sleep=sleep,
    )
    session.run()
    assert len(sleeps) == 4
    np.testing.assert_allclose(sleeps, cable_env.control_dt - 0.010)
