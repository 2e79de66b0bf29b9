"""One cell: its command runs logged, a completion record marks it done, failures carry the end of
the log, and a record made for another command is refused instead of silently re-used.

The commands here are small Python one-liners (the venv's ``python`` as a console script), so
the checks run in well under a second each.
"""

from __future__ import annotations

from pathlib import Path

from rmb_lerobot.benchmark.cells import (
    Cell,
    CellResult,
    execute,
    log_tail,
    parse_final_loss,
    parse_learning_curve,
    recorded,
)
from rmb_lerobot.cli.quickstart import Stage


def python_cell(out: Path, code: str, *, output: str = "made.txt", cid: str = "convert/x") -> Cell:
    target = out / output
    code = code.replace("TARGET", repr(str(target)))
    return Cell(
        cid, cid.split("/")[0], Stage("python", ["-c", code]), target, (), out, reset=(target,)
    )


def test_a_successful_cell_is_recorded_and_then_skipped(tmp_path):
    cell = python_cell(tmp_path, "open(TARGET, 'w').write('x'); print('made it')")
    assert recorded(cell) is None
    result = execute(cell, [])
    assert result.ok and result.seconds > 0 and result.durations == {"convert_s": result.seconds}
    assert "made it" in cell.log.read_text() and cell.log.read_text().startswith("$ python -c")
    done = recorded(cell)
    assert done.ok and done.skipped and done.seconds == result.seconds
    # Its artefact removed: it has to run again.
    cell.output.unlink()
    assert recorded(cell) is None


def test_a_failing_cell_reports_the_end_of_its_log_and_leaves_no_record(tmp_path):
    code = "import sys\nfor i in range(100): print('line', i)\nsys.exit('bad option: --x')"
    cell = python_cell(tmp_path, code)
    result = execute(cell, [])
    assert not result.ok and result.failed_cell == cell.id
    assert result.error.startswith("python exited with status 1; end of ")
    assert result.error.endswith("line 98\nline 99\nbad option: --x")
    assert "line 74" not in result.error  # only the last lines
    assert not cell.record.exists() and recorded(cell) is None


def test_a_command_that_leaves_no_artefact_fails(tmp_path):
    result = execute(python_cell(tmp_path, "pass"), [])
    assert not result.ok and "succeeded but left no" in result.error


def test_upstream_failure_skips_the_cell_and_names_the_origin(tmp_path):
    cell = python_cell(tmp_path, "open(TARGET, 'w')", cid="eval/x")
    upstream = CellResult("train/x", "train", ok=False, error="boom", failed_cell="train/x")
    result = execute(cell, [upstream])
    assert not result.ok and result.failed_cell == "train/x"
    assert result.error == "not run: train/x failed: boom"
    assert not cell.log.exists()  # never started


def test_durations_of_upstream_cells_travel_downstream(tmp_path):
    cell = python_cell(tmp_path, "open(TARGET, 'w')", cid="convert/x")
    upstream = CellResult("collect/x", "collect", ok=True, durations={"collect_s": 3})
    result = execute(cell, [upstream])
    assert result.durations == {"collect_s": 3, "convert_s": result.seconds}


def test_a_record_of_another_command_is_refused_not_reused(tmp_path):
    assert execute(python_cell(tmp_path, "open(TARGET, 'w')"), []).ok
    changed = python_cell(tmp_path, "open(TARGET, 'w'); print(2)")
    verdict = recorded(changed)
    assert not verdict.ok and "was done with another command" in verdict.error
    assert str(changed.record) in verdict.error  # what to remove to redo it


def test_partial_output_of_an_earlier_attempt_is_removed_first(tmp_path):
    cell = python_cell(tmp_path, "import os; assert not os.path.exists(TARGET); open(TARGET, 'w')")
    cell.output.write_text("half")
    assert execute(cell, []).ok


def test_log_tail_shows_what_a_terminal_shows(tmp_path):
    log = tmp_path / "x.log"
    log.write_text("start\nbar  10%\rbar  50%\rbar 100%\n\n\nerror: unrecognized --y\n")
    assert log_tail(log) == "start\nbar 100%\nerror: unrecognized --y"
    assert log_tail(log, lines=1) == "error: unrecognized --y"
    assert log_tail(tmp_path / "missing.log").startswith("(no log:")


def test_learning_curve_and_loss_from_lerobot_train_log(tmp_path):
    # Lines as lerobot-train 0.6.1 logs them with --env_eval_freq=2 (progress bar included).
    log = tmp_path / "train.log"
    log.write_text(
        "Training:  50%|#####     | 2/4 [00:00<00:00]INFO 2026-11-24 21:43:14 ot_train.py:641 "
        "step:2 smpl:4 ep:0 epch:0.05 loss:138.786 grdn:417.690 lr:1.0e-05\n"
        "INFO 2026-11-24 21:43:14 ot_train.py:718 Eval policy at step 2\n"
        "INFO 2026-11-24 21:43:15 ot_train.py:738 Suite per_group aggregated: {'rmb_ur5e_insert':"
        " {'avg_sum_reward': 0.0, 'pc_success': 10.0, 'n_episodes': 9}}\n"
        "INFO 2026-11-24 21:43:15 ot_train.py:738 Suite overall aggregated: {'avg_sum_reward': "
        "0.0, 'avg_max_reward': 0.0, 'pc_success': 40.0, 'n_episodes': 5, 'eval_s': 0.5}\n"
        "\rTraining: 100%|##########| 4/4 INFO 2026-11-24 21:43:15 ot_train.py:641 step:4 smpl:8 "
        "ep:0 epch:0.10 loss:74.935 grdn:262.497\n"
        "INFO 2026-11-24 21:43:15 ot_train.py:718 Eval policy at step 4\n"
        "INFO 2026-11-24 21:43:16 ot_train.py:738 Suite overall aggregated: {'avg_sum_reward': "
        "1.0, 'pc_success': 60.0, 'n_episodes': 5}\n"
    )
    assert parse_learning_curve(log) == [
        {"step": 2, "pc_success": 40.0, "n_episodes": 5},
        {"step": 4, "pc_success": 60.0, "n_episodes": 5},
    ]
    assert parse_final_loss(log) == 74.935
    assert parse_learning_curve("no evaluation here") == []
    assert parse_final_loss("nothing") is None
