"""The table of environments users read first (the README's), made from the registry.

One row per registered simulated env: simulator, robot, task, LeRobot ``--env.type``, the
joint-mode action layout (from the robot record: per arm its joints and gripper, then the base
velocity of a mobile robot) and the cameras. Written between two markers of a markdown file,
so the README's table is never edited by hand and never out of date
(``tests/envs/test_catalog.py`` fails until it is rewritten):

    .venv/bin/python -m rmb_lerobot.envs.catalog README.md
"""

from __future__ import annotations

import sys
from pathlib import Path

from rmb_lerobot.envs.registry import ENVS, EnvEntry
from rmb_lerobot.envs.robots import Arm, Robot
from rmb_lerobot.envs.simulators import SIMULATORS

START = "<!-- env-table:start (made by `python -m rmb_lerobot.envs.catalog README.md`) -->"
END = "<!-- env-table:end -->"


def _number(value: float) -> str:
    return f"{value:.3g}"


def arm_layout(arm: Arm) -> str:
    """``6 joints + gripper 0..255`` (the gripper's command range in its own units)."""
    low, high = arm.gripper.command_range
    return (
        f"{len(arm.joints)} joints + {arm.gripper.kind.value} gripper "
        f"{_number(low)}..{_number(high)}"
    )


def action_layout(robot: Robot) -> str:
    """The joint-mode action of a robot, e.g. ``14: left (6 joints + ...), right (...)``.

    Args:
        robot: The robot record.

    Returns:
        Its size, then what the numbers are in order (RMB's order: arm by arm, each arm's
        joints then its gripper, then the base velocity of a mobile robot).
    """
    if len(robot.arms) == 1:
        parts = [arm_layout(robot.arms[0])]
    else:
        parts = [f"{arm.name}: {arm_layout(arm)}" for arm in robot.arms]
    if robot.base is not None:
        parts.append("base velocity vx, vy, wz (base frame)")
    return f"{robot.command_size}: " + "; ".join(parts)


def row(entry: EnvEntry) -> str:
    """One table row for a registered env."""
    robot = entry.robot_record
    cells = (
        SIMULATORS[entry.simulator].name,
        robot.rmb_name,
        entry.task,
        f"`{entry.lerobot_type}`",
        action_layout(robot),
        ", ".join(entry.cameras),
    )
    return "| " + " | ".join(cells) + " |"


def env_table(entries: list[EnvEntry] | None = None) -> str:
    """The markdown table of the given envs (default: every registered simulated env)."""
    entries = list(ENVS.values()) if entries is None else entries
    header = (
        "| simulator | robot | task | LeRobot `--env.type` | action (joint mode) | cameras |\n"
        "|---|---|---|---|---|---|"
    )
    return "\n".join([header, *(row(entry) for entry in entries)])


def rewrite(path: Path) -> bool:
    """Write the current table between the markers of ``path``; True if it changed.

    Raises:
        ValueError: If ``path`` lacks either marker.
    """
    text = path.read_text()
    if START not in text or END not in text:
        raise ValueError(f"{path}: expected the markers {START!r} and {END!r}")
    before, rest = text.split(START, 1)
    _, after = rest.split(END, 1)
    new = f"{before}{START}\n{env_table()}\n{END}{after}"
    path.write_text(new)
    return new != text


def main(argv: list[str] | None = None) -> int:
    """``python -m rmb_lerobot.envs.catalog FILE...``: rewrite each file's env table."""
    paths = [Path(arg) for arg in (sys.argv[1:] if argv is None else argv)]
    if not paths:
        print("usage: python -m rmb_lerobot.envs.catalog FILE.md [FILE.md ...]", file=sys.stderr)
        return 2
    for path in paths:
        print(f"{path}: {'rewritten' if rewrite(path) else 'up to date'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
