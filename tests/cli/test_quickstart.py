"""The README's main job: collect -> convert -> lerobot-train (ACT) -> lerobot-eval, tiny."""

import json
import re

import pytest

from rmb_lerobot.cli.quickstart import main, parse_args, pipeline

TINY = [
    "--episodes=2",
    "--workers=1",
    "--cameras",
    "front",
    "--image-size",
    "32",
    "32",
    "--steps=2",
    "--batch-size=2",
    "--eval-episodes=1",
    "--episode-length=8",
]


def test_the_pipeline_is_the_four_unmodified_command_line_tools(tmp_path):
    stages = pipeline(parse_args(["--out", str(tmp_path), "--env", "MujocoUR5eDoor"]))

    assert [stage.name for stage in stages] == [
        "rmb-collect",
        "rmb-convert",
        "lerobot-train",
        "lerobot-eval",
        "lerobot-eval",  # again on object placements no demo showed
    ]
    collect, convert, train, evaluate, unseen = stages
    assert str(collect).startswith("rmb-collect MujocoUR5eDoor --episodes=30")
    assert str(convert).startswith(f"rmb-convert to-lerobot {tmp_path / 'rmb'}")
    for stage in (train, evaluate):  # trained and evaluated on the same env type and inputs
        assert {
            "--env.type=rmb_ur5e_door",
            "--env.cameras=[front,hand]",
            "--env.image_width=64",
            "--env.image_height=64",
        } <= set(stage.args)
    assert {"--policy.type=act", "--policy.pretrained_backbone_weights=null"} <= set(train.args)
    # LeRobot's own AdamW preset for ACT; --fused-adamw replaces it by the same AdamW, fused.
    assert not [a for a in train.args if a.startswith(("--optimizer.", "--use_policy_training"))]
    fused = pipeline(parse_args(["--out", str(tmp_path), "--fused-adamw"]))[2]
    assert {
        "--use_policy_training_preset=false",
        "--optimizer.type=adamw_fused",
        "--optimizer.lr=0.0001",
        "--optimizer.weight_decay=0.0001",
        "--scheduler.type=constant_with_warmup",
        "--scheduler.num_warmup_steps=0",
    } <= set(fused.args)
    assert "--workers=1" in convert.args  # one process beats two on 30 short episodes
    assert f"--policy.path={tmp_path}/train/checkpoints/last/pretrained_model" in evaluate.args
    # The unseen evaluation: the same policy and env, objects shifted 2 cm, its own seeds.
    assert set(evaluate.args) - set(unseen.args) == {"--seed=1001", f"--output_dir={tmp_path}/eval"}
    assert set(unseen.args) - set(evaluate.args) == {
        "--env.random_shift=0.02",
        "--seed=2001",
        f"--output_dir={tmp_path}/eval_unseen",
    }
    plain = pipeline(parse_args(["--out", str(tmp_path), "--unseen-shift=0"]))
    assert [stage.name for stage in plain][-2:] == ["lerobot-train", "lerobot-eval"]


def test_an_unknown_env_is_refused_before_anything_runs(tmp_path):
    with pytest.raises(ValueError, match="unknown RMB environment 'MujocoUR5eNope'"):
        main(["--out", str(tmp_path / "qs"), "--env", "MujocoUR5eNope"])
    assert not (tmp_path / "qs").exists()


@pytest.mark.timeout(1200)  # lerobot-train + lerobot-eval subprocesses: 140-160 s in CI
def test_main_job_end_to_end_at_a_tiny_size(tmp_path, capsys):
    out = tmp_path / "qs"

    # With the opt-in fused AdamW: the ALOHA and HSR end-to-end tests train with the preset.
    assert main(["--out", str(out), *TINY, "--fused-adamw"]) == 0

    printed = capsys.readouterr().out
    assert re.search(r"success rate: \d+\.\d % \([01]/1 episodes\)", printed)
    assert re.search(
        r"unseen: +\d+\.\d % \([01]/1 episodes\) with objects shifted up to 2 cm", printed
    )
    episodes = sorted(p.name for p in (out / "rmb").iterdir())
    assert episodes == ["MujocoUR5eInsert_world0_000.rmb", "MujocoUR5eInsert_world1_001.rmb"]
    info = json.loads((out / "dataset" / "meta" / "info.json").read_text())
    assert info["total_episodes"] == 2 and "observation.images.front" in info["features"]
    policy = out / "train" / "checkpoints" / "last" / "pretrained_model"
    assert json.loads((policy / "config.json").read_text())["type"] == "act"
    train_config = json.loads((policy / "train_config.json").read_text())
    assert train_config["optimizer"]["type"] == "adamw_fused"  # lerobot-train took our type
    eval_info = json.loads((out / "eval" / "eval_info.json").read_text())
    assert eval_info["overall"]["n_episodes"] == 1
    assert all(p.endswith(".mp4") for p in eval_info["overall"]["video_paths"])
    assert f"dataset:      {out / 'dataset'}" in printed


# --out: never delete what rmb-quickstart did not create (issue 30).


def _no_stages(monkeypatch) -> list[str]:
    """Replace the stage runner and the summary, so main() only prepares --out."""
    from rmb_lerobot.cli import quickstart

    ran: list[str] = []
    monkeypatch.setattr(quickstart, "run", lambda stage, index, total: ran.append(stage.name) or 0)
    monkeypatch.setattr(quickstart, "report", lambda out, timings, unseen_shift=0.0: [])
    return ran


def test_a_non_empty_out_it_did_not_make_is_refused_and_left_alone(tmp_path, capsys, monkeypatch):
    ran = _no_stages(monkeypatch)
    out = tmp_path / "mine"
    (out / "train").mkdir(parents=True)
    planted = out / "notes.txt"
    planted.write_text("my notes")

    with pytest.raises(SystemExit) as info:
        main(["--out", str(out)])

    assert info.value.code == 2 and ran == []
    error = capsys.readouterr().err
    assert f"--out {out}: not empty and not made by rmb-quickstart" in error
    assert "--reuse-out" in error
    assert planted.read_text() == "my notes" and (out / "train").is_dir()


def test_a_rerun_into_its_own_out_replaces_only_its_stage_folders(tmp_path, monkeypatch):
    ran = _no_stages(monkeypatch)
    out = tmp_path / "qs"
    assert main(["--out", str(out)]) == 0  # a new directory: made and marked
    assert (out / ".rmb-quickstart").is_file() and len(ran) == 5
    for stage in ("rmb", "dataset", "train", "eval"):
        (out / stage / "sub").mkdir(parents=True)
        (out / stage / "sub" / "old").write_text("earlier run")
    planted = out / "notes.txt"
    planted.write_text("my notes")
    (out / "plots").mkdir()

    assert main(["--out", str(out)]) == 0

    assert planted.read_text() == "my notes" and (out / "plots").is_dir()
    assert sorted(p.name for p in out.iterdir()) == [".rmb-quickstart", "notes.txt", "plots"]


def test_reuse_out_uses_a_foreign_directory_without_deleting_anything(tmp_path, monkeypatch):
    from rmb_lerobot.cli.quickstart import OutDirError, prepare_out

    _no_stages(monkeypatch)
    out = tmp_path / "shared"
    out.mkdir()
    planted = out / "notes.txt"
    planted.write_text("my notes")

    assert main(["--out", str(out), "--reuse-out"]) == 0
    assert planted.read_text() == "my notes" and (out / ".rmb-quickstart").is_file()

    other = tmp_path / "other"
    (other / "dataset").mkdir(parents=True)  # a folder of the user's that a stage would replace
    with pytest.raises(OutDirError, match=rf"--out {other}: already holds dataset"):
        prepare_out(other, reuse=True)
    assert (other / "dataset").is_dir()
    (tmp_path / "file").write_text("x")
    with pytest.raises(OutDirError, match="is a file, expected a directory"):
        prepare_out(tmp_path / "file")
