"""The tactile picture script makes its figure: four moments of a grasp, touch visible."""

import runpy
from pathlib import Path

import numpy as np

SCRIPT = Path(__file__).resolve().parents[2] / "examples" / "tactile_grasp_figure.py"


def test_figure_shows_the_grasp():
    script = runpy.run_path(str(SCRIPT))
    moments = script["record_moments"]((64, 48))
    labels = [label for label, _ in moments]
    assert len(moments) == 4 and labels[0] == "start" and labels[-1].startswith("lifted")
    start, lifted = moments[0][1]["tactile_left"], moments[-1][1]["tactile_left"]
    assert np.abs(lifted.astype(float) - start.astype(float)).mean() > 10  # the press shows
    figure = np.asarray(script["tile"](moments))
    assert figure.shape[1] == 4 * (2 * 64 + 4 + 4)  # four columns of two tactile images
