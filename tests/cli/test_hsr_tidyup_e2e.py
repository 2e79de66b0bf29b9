"""HSR TidyUp end to end (issue 25): mobile-robot expert demos -> rmb-convert -> the unmodified
lerobot-train (a tiny ACT, CPU, nothing downloaded) -> lerobot-eval in ``rmb_hsr_tidyup``.

Every stage is the command-line tool run as a subprocess by ``rmb-quickstart``, here on the
robot with a mobile base: its base velocity ``(vx, vy, wz)`` (RMB's ``command_mobile_omni_vel``
and ``measured_mobile_omni_vel``) travels after the arm joints in the demos, in the dataset's
``action`` and ``observation.state``, in the trained policy's output and in the evaluation.
"""

import json
import re

import numpy as np
import pyarrow.parquet as pq
import pytest

from rmb_lerobot import keys as K
from rmb_lerobot import lerobot_names as N
from rmb_lerobot.cli.quickstart import main
from rmb_lerobot.episode import open_episode

TINY = [
    "--env=MujocoHsrTidyup",
    "--episodes=2",
    "--workers=1",
    "--cameras",
    "head",
    "hand",
    "--image-size",
    "32",
    "32",
    "--steps=2",
    "--batch-size=2",
    "--eval-episodes=1",
    "--episode-length=8",
    "--unseen-shift=0",
]
JOINTS = 6  # arm_lift, arm_flex, arm_roll, wrist_flex, wrist_roll, hand_motor
BASE = slice(JOINTS, JOINTS + 3)


@pytest.mark.timeout(1200)  # lerobot-train + lerobot-eval subprocesses (tests/conftest.py)
def test_hsr_tidyup_collect_convert_train_eval(tmp_path, capsys):
    out = tmp_path / "qs"

    assert main(["--out", str(out), *TINY]) == 0

    demos = sorted((out / "rmb").iterdir())
    assert [p.name for p in demos] == [
        "MujocoHsrTidyup_world0_000.rmb",
        "MujocoHsrTidyup_world1_001.rmb",
    ]
    with open_episode(demos[0]) as episode:
        assert episode[K.COMMAND_JOINT_POS].shape[1] == JOINTS  # the joints only
        drive = np.asarray(episode[K.COMMAND_MOBILE_OMNI_VEL])
        measured = np.asarray(episode[K.MEASURED_MOBILE_OMNI_VEL])
    assert np.abs(drive[:, :2]).max() > 0.1 and np.abs(drive[:, 2]).max() > 0.1  # it drove

    dataset = out / "dataset"
    info = json.loads((dataset / "meta" / "info.json").read_text())
    assert info["robot_type"] == "hsr" and info["total_episodes"] == 2
    assert info["features"][N.ACTION_KEY]["shape"] == [JOINTS + 3]
    assert info["features"][N.STATE]["shape"] == [JOINTS + 3]
    assert {"observation.images.head", "observation.images.hand"} <= set(info["features"])
    frames = pq.read_table(sorted((dataset / "data").rglob("*.parquet"))[0]).to_pandas()
    first = frames[frames["episode_index"] == 0]
    action = np.stack(first[N.ACTION_KEY].to_numpy())
    state = np.stack(first[N.STATE].to_numpy())
    # The base velocity is the last three numbers of the action and of the state.
    np.testing.assert_allclose(action[:, BASE], drive, atol=1e-6)
    np.testing.assert_allclose(state[:, BASE], measured, atol=1e-6)

    policy = out / "train" / "checkpoints" / "last" / "pretrained_model"
    config = json.loads((policy / "config.json").read_text())
    assert config["type"] == "act"
    assert config["output_features"][N.ACTION_KEY]["shape"] == [JOINTS + 3]
    eval_info = json.loads((out / "eval" / "eval_info.json").read_text())
    assert eval_info["overall"]["n_episodes"] == 1
    assert all(p.endswith(".mp4") for p in eval_info["overall"]["video_paths"])
    assert re.search(r"success rate: \d+\.\d % \([01]/1 episodes\)", capsys.readouterr().out)
