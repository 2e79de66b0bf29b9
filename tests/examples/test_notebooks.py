"""Every notebook in examples/ runs top to bottom (code cells executed in one namespace, as
Jupyter does) and shows what its text says: each cell's printed output and its displayed value
(the last expression) are checked."""

from __future__ import annotations

import ast
import contextlib
import io
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import nbformat
import numpy as np
import pytest

NOTEBOOKS = sorted((Path(__file__).resolve().parents[2] / "examples").glob("*.ipynb"))


@dataclass
class Cell:
    """What a code cell showed: its printed text and its displayed value (None if none)."""

    printed: str
    value: Any


def run_notebook(notebook: Path) -> tuple[list[Cell], dict]:
    """Execute the code cells in order in one namespace; Jupyter's display of the last
    expression is kept as ``Cell.value``."""
    namespace: dict = {"__name__": "__main__"}
    shown = []
    for number, cell in enumerate(nbformat.read(notebook, as_version=4).cells):
        if cell.cell_type != "code":
            continue
        name = f"{notebook.name}[cell {number}]"
        tree = ast.parse(cell.source, name)
        last = tree.body.pop() if tree.body and isinstance(tree.body[-1], ast.Expr) else None
        out = io.StringIO()
        value = None
        with contextlib.redirect_stdout(out):
            exec(compile(tree, name, "exec"), namespace)
            if last is not None:
                value = eval(compile(ast.Expression(last.value), name, "eval"), namespace)
        shown.append(Cell(out.getvalue(), value))
    return shown, namespace


def check_rmb_episodes(cells: list[Cell], ns: dict) -> None:
    _, record, read, pose, cloud, switch = cells
    # The .rmb variant: a directory of one HDF5 file and a video per camera and kind.
    assert record.value == [
        "front_depth_image.rmb.mp4",
        "front_rgb_image.rmb.mp4",
        "hand_depth_image.rmb.mp4",
        "hand_rgb_image.rmb.mp4",
        "main.rmb.hdf5",
    ]
    assert "fps: 31.25 cameras: ['front', 'hand']" in read.printed
    joints_shape, eef, rgb_shape, rgb_dtype, depth_dtype, depth_min, depth_max = read.value
    assert joints_shape == (10, 7) and eef.shape == (7,)  # 6 joints + gripper; xyz + quaternion
    assert (rgb_shape, rgb_dtype, depth_dtype) == ((120, 160, 3), np.uint8, np.float32)
    assert 0 < depth_min < depth_max < 10  # metres
    assert pose.value.shape == (9,)  # position + 6-D rotation
    shape, low, high = cloud.value
    assert shape == (512, 6) and np.all(low < high)  # xyz + rgb, a 3-D spread
    assert switch.printed.split() == ["EpisodeFormat.SINGLE_HDF5", "60", "(60,", "120,", "160)"]


def check_sim_to_lerobot(cells: list[Cell], ns: dict) -> None:
    _, env, collect, dataset, features_map, step = cells
    assert "| world 3" in env.printed and "{'front': (64, 64, 3)}" in env.printed
    assert [r.success for r in ns["results"]] == [True, True]  # the expert solved both
    assert "MujocoUR5eInsert_world0_000.rmb" in collect.printed
    n_frames = sum(r.steps for r in ns["results"])
    assert f"2 episodes, {n_frames} frames at" in dataset.printed
    assert "'action': (4, 7)" in dataset.printed  # the 4 delta timestamps asked for
    assert "'observation.images.front': (3, 64, 64)" in dataset.printed
    assert "'pixels/front': 'observation.images.front'" in features_map.printed
    assert " M parameters, loss " in step.printed and math.isfinite(float(step.printed.split()[-1]))


CHECKS: dict[str, Callable[[list[Cell], dict], None]] = {
    "01_rmb_episodes": check_rmb_episodes,
    "02_sim_to_lerobot": check_sim_to_lerobot,
}


@pytest.mark.timeout(600)  # 02 collects, converts and loads a dataset: 150 s on a loaded machine
@pytest.mark.parametrize("notebook", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_runs_and_shows_what_it_says(notebook, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert notebook.stem in CHECKS, f"no output checks for {notebook.name}: add them to CHECKS"
    cells, namespace = run_notebook(notebook)
    CHECKS[notebook.stem](cells, namespace)


def test_there_are_notebooks():
    assert [p.stem for p in NOTEBOOKS] == sorted(CHECKS)
