"""LeRobot decodes our datasets without printing torchcodec's loading traceback.

``lerobot[dataset]`` pulls in torchcodec, which needs FFmpeg 4-8 shared libraries that no PyPI
package provides. Installed without them, every LeRobot command printed a 100-line "Could not
load libtorchcodec" traceback before falling back to PyAV, which reads as a failure. Our lock
leaves torchcodec out (``[tool.uv] override-dependencies``), so LeRobot picks PyAV, whose wheels
bundle FFmpeg. Each check runs in a fresh interpreter, as a user's command would.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from rmb_lerobot import keys as K
from rmb_lerobot import lerobot_names as N
from rmb_lerobot import open_episode

NOISE = ("Could not load libtorchcodec", "libtorchcodec", "Traceback")

# What lerobot-train does with a dataset: LeRobot's own default decoder (no video_backend
# given), LeRobot's logging switched on, frames read through LeRobotDataset.__getitem__.
READ_DATASET = """
import json, logging, sys
logging.basicConfig(level=logging.INFO)
from lerobot.datasets.lerobot_dataset import LeRobotDataset
root = sys.argv[1]
dataset = LeRobotDataset("local/noise", root=root)
frames = {i: dataset[i][sys.argv[2]] for i in (0, len(dataset) - 1)}
print(json.dumps({
    "length": len(dataset),
    "frames": {i: (f.permute(1, 2, 0) * 255).tolist() for i, f in frames.items()},
}))
"""


def _run(args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, *args], capture_output=True, text=True, cwd=cwd, check=False, timeout=300
    )


def _assert_quiet(stderr: str) -> None:
    for marker in NOISE:
        assert marker not in stderr, stderr[-3000:]


def test_torchcodec_is_absent_or_loads(tmp_path):
    # Installed but unloadable is the state that printed the traceback; LeRobot's own probe
    # must see either no torchcodec or a working one.
    probe = _run(
        [
            "-c",
            "import logging; logging.basicConfig(level=logging.INFO)\n"
            "from lerobot.utils.import_utils import get_safe_default_video_backend\n"
            "print(get_safe_default_video_backend())",
        ],
        tmp_path,
    )
    assert probe.returncode == 0, probe.stderr[-3000:]
    assert probe.stdout.strip() in ("pyav", "torchcodec")
    _assert_quiet(probe.stderr)
    assert "cannot be loaded" not in probe.stderr


@pytest.mark.timeout(900)  # rmb-convert, then LeRobot's loader: two fresh interpreters
def test_converted_dataset_decodes_without_torchcodec_noise(tmp_path, record):
    episode = record(tmp_path / "episodes" / "demo.rmb")
    root = tmp_path / "dataset"
    convert = _run(
        [
            "-m",
            "rmb_lerobot.cli.convert",
            "to-lerobot",
            str(episode.parent),
            f"--output={root}",
            "--repo-id=local/noise",
            "--video-codec=h264",
        ],
        tmp_path,
    )
    assert convert.returncode == 0, convert.stderr[-3000:]
    _assert_quiet(convert.stderr)
    # Only writing happens there: the converter names its backend, so LeRobot never probes
    # torchcodec (not even its one-line "not available" warning).
    assert "torchcodec" not in convert.stderr, convert.stderr[-3000:]

    read = _run(["-c", READ_DATASET, str(root), N.image_key("front")], tmp_path)
    assert read.returncode == 0, read.stderr[-3000:]
    _assert_quiet(read.stderr)
    result = json.loads(read.stdout.splitlines()[-1])
    with open_episode(episode) as ep:
        source = ep[K.rgb_image_key("front")][:]
        assert result["length"] == len(ep)
    for index, frame in result["frames"].items():
        decoded = np.asarray(frame, dtype=np.float32)
        expected = source[int(index)].astype(np.float32)
        assert decoded.shape == expected.shape
        # Two lossy H.264 passes (RMB's video, then LeRobot's): close, not equal.
        assert np.abs(decoded - expected).mean() < 6.0
