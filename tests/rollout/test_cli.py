"""``rmb-rollout`` and ``rmb-rollout-client``: the client against a served stub, and the whole
path with the MT-ACT plugin: lerobot-train on a tiny Pick dataset, then one instruction over
the socket to ``rmb-rollout`` running the checkpoint."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from rmb_lerobot.cli import rollout, rollout_client
from rmb_lerobot.rollout import RolloutClient, RolloutError

BANANA, APPLE = "Put the banana in the blue basket.", "Put the apple in the black basket."


def run_client(capsys, *args: str) -> tuple[int, list[dict]]:
    code = rollout_client.main(list(args))
    out = capsys.readouterr().out
    return code, [json.loads(line) for line in out.splitlines()]


def test_client_cli_waits_for_the_result_and_exits_by_it(capsys, make_push_env, policy, serving):
    env = make_push_env(max_steps=5)
    with serving(env, policy, "tcp:127.0.0.1:0") as server:
        address = str(server.address)
        code, replies = run_client(capsys, BANANA, "--connect", address, "--timeout", "10")
        assert code == 0
        assert [r["status"] for r in replies] == ["started", "success"]
        assert replies[1]["steps"] == 3

        code, replies = run_client(capsys, APPLE, "--connect", address, "--timeout", "10")
        assert code == 1 and replies[1]["reason"] == "max_steps"

        code, replies = run_client(capsys, "--done", "--connect", address, "--timeout", "10")
        assert code == 2 and replies == [
            {
                "status": "error",
                "error": "not_running",
                "message": "no episode is running",
                "request": "done",
            }
        ]


def test_client_cli_no_wait_then_done(capsys, make_push_env, policy, serving):
    env = make_push_env(max_steps=10**9, goal=float("inf"))
    with serving(env, policy, "tcp:127.0.0.1:0") as server:
        address = str(server.address)
        code, replies = run_client(capsys, APPLE, "--no-wait", "--connect", address)
        assert code == 0 and [r["status"] for r in replies] == ["started"]
        code, replies = run_client(capsys, "--done", "--connect", address, "--timeout", "10")
        assert code == 1
        assert (replies[0]["status"], replies[0]["reason"], replies[0]["episode"]) == (
            "failure",
            "done",
            0,
        )


def test_client_cli_errors(capsys, sock_path):
    assert rollout_client.main([BANANA, "--connect", f"unix:{sock_path}"]) == 3  # no server
    assert "rmb-rollout-client" in capsys.readouterr().err
    usage = ([], [BANANA, "--done"], ["done"], ["--done", "--no-wait"], [BANANA, "--connect", "x"])
    for bad in usage:
        with pytest.raises(SystemExit) as exit_:
            rollout_client.main(bad)
        assert exit_.value.code == 2


def test_server_cli_refuses_bad_arguments_before_loading_anything(tmp_path, capsys):
    code = rollout.main([str(tmp_path), "--env.type=rmb_ur5e_pick", "--listen", "tcp:0.0.0.0:0"])
    assert code == 2 and "--allow-remote" in capsys.readouterr().err
    for bad in (
        [str(tmp_path)],  # no --env.type
        [str(tmp_path), "--env.type=rmb_ur5e_pick", "--listen", "sock"],
        [str(tmp_path), "--env.type=rmb_ur5e_pick", "--bogus"],
        [str(tmp_path), "--env.type=rmb_ur5e_pick", "--episodes", "0"],
    ):
        with pytest.raises(SystemExit) as exit_:
            rollout.main(bad)
        assert exit_.value.code == 2


# ---------------------------------------------------------------- end to end with MT-ACT
TINY_MT_ACT = [
    "--policy.dim_model=32",
    "--policy.n_heads=2",
    "--policy.dim_feedforward=64",
    "--policy.n_encoder_layers=1",
    "--policy.n_decoder_layers=1",
    "--policy.n_vae_encoder_layers=1",
    "--policy.latent_dim=8",
    "--policy.chunk_size=4",
    "--policy.n_action_steps=4",
]
ENV_ARGS = [
    "--env.type=rmb_ur5e_pick",
    "--env.cameras=[front]",
    "--env.image_width=32",
    "--env.image_height=32",
]


@pytest.fixture(scope="module")
def mt_act_checkpoint(tmp_path_factory, make_expert_dataset, lerobot_cli) -> Path:
    """MT-ACT trained 3 steps (lerobot-train) on one scripted Pick demonstration (32x32)."""
    root = tmp_path_factory.mktemp("mt_act")
    dataset = make_expert_dataset("pick", root / "pick", world_idx=(0,), size=32)
    out = root / "train"
    train = lerobot_cli(
        "lerobot_train",
        [
            "--policy.type=mt_act",
            *TINY_MT_ACT,
            "--policy.device=cpu",
            "--policy.push_to_hub=false",
            "--dataset.repo_id=local/pick",
            f"--dataset.root={dataset}",
            f"--output_dir={out}",
            "--steps=3",
            "--batch_size=2",
            "--num_workers=0",
            "--save_freq=3",
            "--wandb.enable=false",
        ],
        root,
    )
    assert train.returncode == 0, train.stderr[-3000:]
    return out / "checkpoints" / "last" / "pretrained_model"


def test_rollout_cli_runs_mt_act_with_an_instruction_from_the_socket(
    mt_act_checkpoint, sock_path, capsys
):
    """``rmb-rollout`` in this process (its imports are already paid for) on the main thread, as
    from a shell; a client thread sends the instruction, then SIGTERM as a user's Ctrl-C."""
    address = f"unix:{sock_path}"
    replies: dict = {}

    def client() -> None:
        deadline = time.monotonic() + 300
        while not sock_path.exists():
            if time.monotonic() > deadline:
                return
            time.sleep(0.1)
        try:
            with RolloutClient(address, timeout=120) as c:
                replies["started"] = c.instruct(BANANA)
                replies["result"] = c.result()
                with pytest.raises(RolloutError) as refused:
                    c.instruct("Juggle.")
                replies["refused"] = refused.value.reply
        finally:
            os.kill(os.getpid(), signal.SIGTERM)

    thread = threading.Thread(target=client)
    thread.start()
    code = rollout.main(
        [
            str(mt_act_checkpoint),
            *ENV_ARGS,
            "--env.episode_length=4",
            "--listen",
            address,
            "--device",
            "cpu",
        ]
    )
    thread.join(timeout=60)
    out = capsys.readouterr().out
    assert code == 128 + signal.SIGTERM
    assert not sock_path.exists()  # removed on the way out
    assert replies["started"] == {"status": "started", "episode": 0, "instruction": BANANA}
    result = replies["result"]  # 3 training steps: no success within 4 steps
    assert (result["status"], result["reason"], result["steps"]) == ("failure", "max_steps", 4)
    assert replies["refused"]["error"] == "bad_instruction"  # Pick's env knows 18 instructions
    assert f"listening on {address}" in out
    results = [json.loads(line)["episode_result"] for line in out.splitlines() if "{" in line]
    assert [(r["instruction"], r["status"], r["steps"]) for r in results] == [
        (BANANA, "failure", 4)
    ]


def test_rollout_cli_ctrl_c_aborts_the_episode_and_exits_130(mt_act_checkpoint, sock_path):
    """A real ``rmb-rollout`` process, as from a shell: Ctrl-C (SIGINT) mid-episode aborts the
    episode for its client, removes the socket file and exits with 130."""
    address = f"unix:{sock_path}"
    command = [sys.executable, "-m", "rmb_lerobot.cli.rollout", str(mt_act_checkpoint)]
    command += [*ENV_ARGS, "--env.episode_length=100000", "--listen", address, "--device", "cpu"]
    process = subprocess.Popen(
        command,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "HF_HUB_OFFLINE": "1", "OMP_NUM_THREADS": "1"},
    )
    try:
        deadline = time.monotonic() + 600
        while not sock_path.exists():
            if process.poll() is not None:
                pytest.fail(f"rmb-rollout ended early: {process.communicate()[1][-3000:]}")
            assert time.monotonic() < deadline, "rmb-rollout never listened"
            time.sleep(0.2)
        with RolloutClient(address, timeout=120) as client:
            assert client.instruct(BANANA)["status"] == "started"
            process.send_signal(signal.SIGINT)  # what Ctrl-C sends
            result = client.result()
        _, stderr = process.communicate(timeout=120)
    finally:
        if process.poll() is None:
            process.kill()
            process.communicate()
    assert (result["status"], result["reason"]) == ("aborted", "shutdown")
    assert process.returncode == 130, stderr[-3000:]
    assert "stopped by SIGINT; socket closed" in stderr
    assert not sock_path.exists()
