"""rmb-data view: an episode as a rerun recording (cameras, clouds, plots, tactile grids)."""

import sys

import numpy as np
import pytest

from rmb_lerobot.data.add_pointcloud import PointCloudOptions, add_pointclouds
from rmb_lerobot.data.view import import_rerun, view_episode

pytest.importorskip("rerun", reason="the viz extra (rerun-sdk) is not installed")
from rerun.experimental import RrdReader


def _rows(rrd):
    """Entity path -> number of logged (non-static) rows, read back from the file."""
    store = RrdReader(str(rrd)).store()
    rows = {}
    for chunk in store.stream().to_chunks():
        if not chunk.is_static:
            rows[chunk.entity_path] = rows.get(chunk.entity_path, 0) + chunk.num_rows
    return rows, store.schema().entity_paths()


def tactile(i):
    grid = np.zeros((5, 8))
    grid[i % 5, i % 8] = 1.0 + i
    return {"left_tactile_sensor": grid}


def test_recording_holds_every_camera_plot_cloud_and_tactile_grid(tmp_path, record_with):
    path = record_with(tmp_path / "ep.rmb", extra=tactile)
    add_pointclouds([path], ["front"], PointCloudOptions(num_points=32), progress=False)
    rrd = view_episode(path, save=tmp_path / "out" / "ep.rrd", progress=False)
    assert rrd == tmp_path / "out" / "ep.rrd" and rrd.stat().st_size > 10_000
    rows, entities = _rows(rrd)
    for camera in ("front", "hand"):
        assert rows[f"/cameras/{camera}/rgb"] == 12 and rows[f"/cameras/{camera}/depth"] == 12
        assert f"/cameras/{camera}" in entities  # the pinhole from fovy: depth shown in 3D
    assert rows["/cameras/front/pointcloud"] == 12 and "/cameras/hand/pointcloud" not in rows
    for key in ("measured_joint_pos", "command_eef_pose", "measured_eef_wrench", "reward"):
        assert rows[f"/plots/{key}"] == 12, key
    assert "/plots/time" not in rows  # time is the timeline, not a plot
    assert rows["/tactile/left_tactile_sensor/values"] == 12
    assert rows["/tactile/left_tactile_sensor/heatmap"] == 12
    assert "/episode" in entities
    assert not [p for p in rrd.parent.iterdir() if p.name.startswith(".")]


def test_stride_and_default_file_without_display(tmp_path, record, monkeypatch):
    path = record(tmp_path / "ep.hdf5")
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setattr(sys, "platform", "linux")
    monkeypatch.chdir(tmp_path)
    rrd = view_episode(path, stride=5, progress=False)  # no display: a file, not a viewer
    assert rrd.name == "ep.rrd" and (tmp_path / "ep.rrd").is_file()
    rows, _ = _rows(tmp_path / "ep.rrd")
    assert rows["/cameras/front/rgb"] == 3 and rows["/plots/measured_joint_pos"] == 3  # 0, 5, 10


def test_missing_rerun_names_the_viz_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "rerun", None)
    with pytest.raises(ImportError, match=r"viz\]"):
        import_rerun()
