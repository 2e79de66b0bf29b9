"""Every plugin policy trains under LeRobot's multi-process path (accelerate launch lerobot-train).

Two CPU processes stand in for two GPUs (or nodes): accelerate's ``--multi_gpu`` launcher starts
them with torchrun and, as ``--policy.device=cpu`` makes LeRobot build ``Accelerator(cpu=True)``,
they train with DistributedDataParallel over gloo. (``accelerate launch --cpu --num_processes 2``
would start only ONE process: accelerate's CPU launcher needs mpirun for more.)

A new plugin is one more entry in :data:`PLUGINS`.
"""

from __future__ import annotations

import itertools
import json
import os
import shutil
import signal
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
import torch
from lerobot.configs import RGBEncoderConfig, depth_encoder_defaults
from lerobot.datasets import LeRobotDataset
from lerobot.policies.factory import make_pre_post_processors
from lerobot.policies.pretrained import PreTrainedPolicy
from safetensors.torch import load_file

from rmb_lerobot.policies_extra.dp3 import DP3Policy
from rmb_lerobot.policies_extra.flow_policy import FlowPolicy
from rmb_lerobot.policies_extra.maniflow import ManiFlowPolicy
from rmb_lerobot.policies_extra.mlp import MLPPolicy
from rmb_lerobot.policies_extra.mt_act import MTACTPolicy
from rmb_lerobot.policies_extra.sarnn import SARNNPolicy

STATE_DIM = ACTION_DIM = 7
SIZE = 32
FPS = 31
EPISODES, EPISODE_LEN = 2, 24
FRONT = "observation.images.front"
DEPTH = "observation.images.front_depth"
PROCESSES, BATCH, STEPS = 2, 2, 3
# A run that has not ended by then is stuck (a normal one takes 1-4 minutes on a loaded 2-core
# machine): it fails with py-spy dumps of its processes (if py-spy is installed) instead of
# holding CI until the test's own limit. LeRobot's teardown hang is avoided in ddp_observer.py.
LAUNCH_TIMEOUT_S = 600

OBSERVER = Path(__file__).with_name("ddp_observer.py")


@dataclass(frozen=True)
class Plugin:
    policy_class: type[PreTrainedPolicy]
    args: tuple[str, ...]  # tiny sizes, so that a few steps cost little


# The MLP's ResNet takes RGB only: its inputs leave the depth camera out.
MLP_INPUTS = json.dumps(
    {
        "observation.state": {"type": "STATE", "shape": [STATE_DIM]},
        FRONT: {"type": "VISUAL", "shape": [3, SIZE, SIZE]},
    }
)
PLUGINS = {
    "mlp": Plugin(
        MLPPolicy,
        (
            "--policy.chunk_size=4",
            "--policy.n_action_steps=2",
            "--policy.hidden_dims=[64]",
            f"--policy.input_features={MLP_INPUTS}",
        ),
    ),
    "sarnn": Plugin(
        SARNNPolicy,
        ("--policy.sequence_length=3", "--policy.frame_skip=2", "--policy.image_size=[16,16]"),
    ),
    "dp3": Plugin(
        DP3Policy,
        (
            "--policy.num_points=64",
            "--policy.down_dims=[32,64]",
            "--policy.horizon=8",
            "--policy.n_action_steps=4",
            "--policy.camera_fovy=45",
            "--policy.scheduler_warmup_steps=0",  # full lr at once: every weight moves visibly
        ),
    ),
    "flow_policy": Plugin(
        FlowPolicy,
        ("--policy.num_points=64", "--policy.down_dims=[32,64]", "--policy.camera_fovy=45"),
    ),
    # Image tokens (the default encoder); RGB only, like the MLP.
    "maniflow": Plugin(
        ManiFlowPolicy,
        (
            "--policy.n_layer=1",
            "--policy.n_head=2",
            "--policy.n_emb=32",
            "--policy.resnet_width=16",
            "--policy.horizon=8",
            "--policy.n_action_steps=4",
            "--policy.scheduler_warmup_steps=0",
            f"--policy.input_features={MLP_INPUTS}",
        ),
    ),
    # The task sentence comes from the dataset's task ("Follow the square.").
    "mt_act": Plugin(
        MTACTPolicy,
        (
            "--policy.dim_model=32",
            "--policy.n_heads=2",
            "--policy.dim_feedforward=64",
            "--policy.n_encoder_layers=1",
            "--policy.n_decoder_layers=1",
            "--policy.n_vae_encoder_layers=1",
            "--policy.latent_dim=8",
            "--policy.chunk_size=4",
            "--policy.n_action_steps=4",
            "--policy.dropout=0",
            f"--policy.input_features={MLP_INPUTS}",
        ),
    ),
}


@pytest.fixture(scope="session")  # built once per worker: xdist runs these tests one by one
def dataset(tmp_path_factory) -> Path:
    """Two synthetic episodes every plugin can train on: state, action, front RGB and depth.

    A square follows joints 0 and 1 in both images (0.6 m above a table at 0.8 m in depth)."""
    root = tmp_path_factory.mktemp("ddp") / "dataset"
    image = {"dtype": "video", "shape": (SIZE, SIZE, 3), "names": ["height", "width", "channels"]}
    writer = LeRobotDataset.create(
        repo_id="local/ddp",
        fps=FPS,
        root=root,
        robot_type="ur5e",
        rgb_encoder=RGBEncoderConfig(vcodec="h264"),
        depth_encoder=depth_encoder_defaults(),
        features={
            "observation.state": {"dtype": "float32", "shape": (STATE_DIM,), "names": None},
            FRONT: image,
            DEPTH: {**image, "shape": (SIZE, SIZE, 1), "info": {"is_depth_map": True}},
            "action": {"dtype": "float32", "shape": (ACTION_DIM,), "names": None},
        },
    )
    freqs = np.linspace(0.5, 1.5, STATE_DIM)
    for episode in range(EPISODES):
        t = np.arange(EPISODE_LEN + 1)[:, None] / FPS
        joints = np.sin(2 * np.pi * freqs * t + episode).astype(np.float32)
        for state, action in itertools.pairwise(joints):
            x, y = ((state[:2] + 1) / 2 * (SIZE - 8)).astype(int)
            rgb = np.zeros((SIZE, SIZE, 3), dtype=np.uint8)
            rgb[y : y + 8, x : x + 8] = (255, 160, 40)
            depth = np.full((SIZE, SIZE, 1), 0.8, dtype=np.float32)
            depth[y : y + 8, x : x + 8] = 0.6
            frame = {"observation.state": state, "action": action, FRONT: rgb, DEPTH: depth}
            writer.add_frame({**frame, "task": "Follow the square."})
        writer.save_episode()
    writer.finalize()
    return root


def accelerate_launch_lerobot_train(
    args: list[str], cwd: Path, observer_dir: Path
) -> subprocess.CompletedProcess:
    """``accelerate launch --multi_gpu --num_processes 2 lerobot-train ARGS``, offline, on CPU."""
    launch = [
        sys.executable,
        "-m",
        "accelerate.commands.launch",
        "--multi_gpu",
        f"--num_processes={PROCESSES}",
        "--num_machines=1",
        "--main_process_port=0",  # a free port: runs in parallel do not collide
        "--num_cpu_threads_per_process=1",
        "--mixed_precision=no",
        "--dynamo_backend=no",
    ]
    env = {
        **os.environ,
        "HF_HUB_OFFLINE": "1",
        "WANDB_MODE": "disabled",
        "DDP_OBSERVER_DIR": str(observer_dir),
    }
    process = subprocess.Popen(
        [*launch, str(OBSERVER), *args],
        cwd=cwd,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,  # the launcher and both ranks: one group to dump and kill
    )
    try:
        stdout, stderr = process.communicate(timeout=LAUNCH_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        dumps = py_spy_dumps(process.pid)
        os.killpg(process.pid, signal.SIGKILL)
        stdout, stderr = process.communicate()
        pytest.fail(
            f"accelerate launch lerobot-train still running after {LAUNCH_TIMEOUT_S} s (a hung "
            f"rank?); killed.\n{dumps}\n--- end of its stderr:\n{stderr[-3000:]}"
        )
    return subprocess.CompletedProcess(process.args, process.returncode, stdout, stderr)


def py_spy_dumps(session: int) -> str:
    """``py-spy dump`` of every process in the launcher's session (where each rank is stuck),
    or why there is none."""
    py_spy = shutil.which("py-spy")
    if py_spy is None:
        return "(install py-spy to get the stacks of a hung run)"
    pids = subprocess.run(
        ["pgrep", "-s", str(session)], capture_output=True, text=True, check=False
    ).stdout.split()
    dumps = []
    for pid in pids:
        dump = subprocess.run(
            [py_spy, "dump", "--pid", pid], capture_output=True, text=True, timeout=60, check=False
        )
        dumps.append(f"--- py-spy dump --pid {pid}\n{dump.stdout}{dump.stderr}")
    return "\n".join(dumps)


def first_observation(dataset: Path) -> dict[str, torch.Tensor]:
    """The first frame as a batch of one, with its task sentence (MT-ACT needs it)."""
    frame = LeRobotDataset("local/ddp", root=dataset)[0]
    batch = {key: value[None] for key, value in frame.items() if key.startswith("observation.")}
    return {**batch, "task": [frame["task"]]}


@pytest.mark.timeout(1200)  # lerobot-train in a subprocess (tests/conftest.py)
@pytest.mark.parametrize("name", PLUGINS)
def test_lerobot_train_runs_data_parallel_on_two_processes(name, dataset, tmp_path):
    plugin = PLUGINS[name]
    out, ranks = tmp_path / "train", tmp_path / "ranks"
    ranks.mkdir()
    train = accelerate_launch_lerobot_train(
        [
            f"--policy.type={name}",
            *plugin.args,
            "--policy.device=cpu",
            "--policy.push_to_hub=false",
            "--dataset.repo_id=local/ddp",
            f"--dataset.root={dataset}",
            f"--output_dir={out}",
            f"--steps={STEPS}",
            f"--batch_size={BATCH}",
            "--num_workers=0",
            f"--save_freq={STEPS}",
            "--log_freq=1",
            "--wandb.enable=false",
        ],
        tmp_path,
        ranks,
    )
    assert train.returncode == 0, train.stderr[-3000:]

    # Both ranks trained: LeRobot saw the world size, and each rank held the DDP-wrapped policy.
    log = train.stdout + train.stderr
    assert f"Effective batch size: {BATCH} x {PROCESSES} = {BATCH * PROCESSES}" in log
    checkpoint = out / "checkpoints" / "last"
    training_step = json.loads((checkpoint / "training_state" / "training_step.json").read_text())
    assert training_step["step"] == STEPS and training_step["num_processes"] == PROCESSES

    # The ranks end in sync, and the main process saved exactly what they hold.
    start, end = (load_file(ranks / f"rank0_{stage}.safetensors") for stage in ("start", "end"))
    rank1 = load_file(ranks / "rank1_end.safetensors")
    saved = load_file(checkpoint / "pretrained_model" / "model.safetensors")
    assert end.keys() == rank1.keys() == saved.keys()
    for key, value in end.items():
        assert torch.equal(value, rank1[key]), f"rank 1 differs from rank 0 in {key}"
        assert torch.equal(value, saved[key]), f"the checkpoint differs from rank 0 in {key}"
        assert not value.is_floating_point() or torch.isfinite(value).all(), key

    # The checkpoint loads with the plugin's from_pretrained and acts.
    policy = plugin.policy_class.from_pretrained(checkpoint / "pretrained_model")
    # Every weight took part in the loss: an unused one would get no gradient and stay put
    # (LeRobot's DDP tolerates that with find_unused_parameters=True, at a cost every step).
    frozen = [key for key, _ in policy.named_parameters() if torch.equal(start[key], end[key])]
    assert not frozen, f"parameters training never changed: {frozen}"
    pre, post = make_pre_post_processors(
        policy.config, pretrained_path=str(checkpoint / "pretrained_model")
    )
    policy.reset()
    action = post(policy.select_action(pre(first_observation(dataset))))
    assert action.shape == (1, ACTION_DIM) and torch.isfinite(action).all()
