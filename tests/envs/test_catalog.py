"""The README's env table is the registry's: one row per env, with its joint-mode action."""

from __future__ import annotations

from pathlib import Path

import pytest

from rmb_lerobot.envs.catalog import END, START, action_layout, env_table, rewrite
from rmb_lerobot.envs.registry import ENVS
from rmb_lerobot.envs.robots import ROBOTS

README = Path(__file__).resolve().parents[2] / "README.md"


def test_the_readme_shows_the_current_env_table():
    table = README.read_text().split(START, 1)[1].split(END, 1)[0].strip()
    assert table == env_table(), "run `.venv/bin/python -m rmb_lerobot.envs.catalog README.md`"


def test_every_env_has_a_row_with_its_type():
    rows = env_table().splitlines()[2:]
    assert len(rows) == len(ENVS)
    for entry, row in zip(ENVS.values(), rows, strict=True):
        assert f"`{entry.lerobot_type}`" in row


@pytest.mark.parametrize("name", sorted(ROBOTS))
def test_the_action_size_is_the_command_size(name):
    robot = ROBOTS[name]
    assert action_layout(robot).startswith(f"{robot.command_size}: ")


def test_action_layouts_say_arms_grippers_and_base():
    assert action_layout(ROBOTS["ur5e"]) == "7: 6 joints + parallel gripper 0..255"
    dual = action_layout(ROBOTS["ur5e_dual"])
    assert dual.startswith("14: left: 6 joints") and "; right: 6 joints" in dual
    mobile = [robot for robot in ROBOTS.values() if robot.base is not None]
    for robot in mobile:
        assert action_layout(robot).endswith("base velocity vx, vy, wz (base frame)")


def test_rewrite_fills_the_markers_and_refuses_a_file_without_them(tmp_path):
    page = tmp_path / "page.md"
    page.write_text(f"# Envs\n\n{START}\nold\n{END}\n\nmore\n")
    assert rewrite(page) is True
    text = page.read_text()
    assert "old" not in text and env_table() in text and text.endswith("\n\nmore\n")
    assert rewrite(page) is False
    bare = tmp_path / "bare.md"
    bare.write_text("no markers\n")
    with pytest.raises(ValueError, match=r"bare\.md: expected the markers"):
        rewrite(bare)
