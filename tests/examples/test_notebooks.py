"""Every notebook in examples/ runs top to bottom (code cells executed in one namespace)."""

from pathlib import Path

import nbformat
import pytest

NOTEBOOKS = sorted((Path(__file__).resolve().parents[2] / "examples").glob("*.ipynb"))


@pytest.mark.parametrize("notebook", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_runs(notebook, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    cells = nbformat.read(notebook, as_version=4).cells
    namespace: dict = {"__name__": "__main__"}
    for number, cell in enumerate(cells):
        if cell.cell_type == "code":
            exec(compile(cell.source, f"{notebook.name}[cell {number}]", "exec"), namespace)


def test_there_are_notebooks():
    assert NOTEBOOKS
