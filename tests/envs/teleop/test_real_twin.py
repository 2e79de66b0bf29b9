"""The teleop loop on a real env (``RealUR5eDemo``, ``driver: sim``): RMB's keys move the real
arm's end effector through the safety layer, and the saved episode is RMB's real format."""

from __future__ import annotations

import numpy as np
import pytest

from rmb_lerobot import keys as K
from rmb_lerobot.envs.real.config import make_real_env
from rmb_lerobot.envs.teleop.keyboard import KeyboardDevice
from rmb_lerobot.envs.teleop.keys import ScriptedKeySource
from rmb_lerobot.envs.teleop.session import TeleopConfig, TeleopSession
from rmb_lerobot.episode import open_episode

# n: -> standby, n: -> teleop, 3 x q (+z), z (gripper +50), hold, n: -> end, s: save.
KEYS = [(0, "n"), (1, "n"), (2, "q"), (3, "q"), (4, "q"), (5, "z"), (20, "n"), (21, "s")]


def test_the_keyboard_drives_the_real_ur5e_twin_and_saves_rmbs_real_episode(tmp_path):
    env = make_real_env(
        "RealUR5eDemo",
        {"driver": "sim", "image_size": (32, 24), "settle_s": 0.02, "reset_scale": 1.0},
    )
    try:
        session = TeleopSession(
            env,
            KeyboardDevice(num_arms=1),
            ScriptedKeySource(KEYS),
            # The real env paces every step to its 50 Hz itself.
            TeleopConfig(out=tmp_path, realtime=False),
            log=lambda message: None,
        )
        session.run()
    finally:
        env.close()
    [path] = session.result.saved
    assert path.name == "RealUR5eDemo_world0_000.rmb"
    with open_episode(path) as ep:
        assert ep.attrs["env"] == "RealUR5eDemoEnv"
        for key in (K.MEASURED_EEF_WRENCH, K.MEASURED_JOINT_VEL, "front_rgb_image"):
            assert key in ep, key
        command, measured = ep[K.COMMAND_EEF_POSE][:], ep[K.MEASURED_EEF_POSE][:]
        # The target rose 3 cm (world z) and the twin's arm followed through the safety layer.
        assert command[-1, 2] - command[0, 2] == pytest.approx(0.03, abs=5e-4)
        assert measured[-1, 2] - measured[0, 2] > 0.02
        np.testing.assert_allclose(command[-1, :2], command[0, :2], atol=5e-4)
        assert ep[K.COMMAND_GRIPPER_JOINT_POS][-1, 0] == 50
        assert np.all(np.diff(ep[K.TIME][:]) > 0.01)  # stamped in wall-clock time at 50 Hz
