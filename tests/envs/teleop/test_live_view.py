"""The live view, headless: a session logs to an .rrd file, read back with rerun's own reader."""

from __future__ import annotations

import pytest

from rmb_lerobot.envs.teleop.keyboard import KeyboardDevice
from rmb_lerobot.envs.teleop.keys import ScriptedKeySource
from rmb_lerobot.envs.teleop.live_view import LiveView
from rmb_lerobot.envs.teleop.session import TeleopConfig, TeleopSession

pytest.importorskip("rerun", reason="the viz extra (rerun-sdk) is not installed")
from rerun.experimental import RrdReader

STEPS = 7  # keys at polls 0..5, Esc at poll 7: seven control steps (Esc ends before stepping)


def read_back(rrd):
    """Entity path -> number of logged (non-static) rows."""
    rows: dict[str, int] = {}
    for chunk in RrdReader(str(rrd)).store().stream().to_chunks():
        if not chunk.is_static:
            rows[chunk.entity_path] = rows.get(chunk.entity_path, 0) + chunk.num_rows
    return rows


def test_a_session_logs_images_targets_and_phases_to_an_rrd(cable_env, tmp_path):
    view = LiveView(tmp_path / "view" / "live.rrd", image_every=2)
    events = [(0, "n"), (1, "n"), (2, "w"), (3, "w"), (4, "n"), (5, "s"), (7, "esc")]
    session = TeleopSession(
        cable_env,
        KeyboardDevice(),
        ScriptedKeySource(events),
        TeleopConfig(out=tmp_path / "episodes", realtime=False),
        view=view,
        log=lambda message: None,
    )
    try:
        session.run()
    finally:
        rrd = view.close()
    assert rrd == tmp_path / "view" / "live.rrd"
    assert [p.name for p in rrd.parent.iterdir()] == ["live.rrd"]  # no temporary left
    rows = read_back(rrd)
    assert session.result.steps == STEPS
    assert rows["/cameras/front/rgb"] == 4  # every second step: steps 1, 3, 5, 7
    assert rows["/eef_target/arm0"] == STEPS and rows["/success/env0"] == STEPS
    # After each step, one entry per change: standby, teleop, end, initial (episode saved).
    assert rows["/phase"] == 4
    assert len(session.result.saved) == 1


def test_a_live_view_file_must_be_an_rrd(tmp_path):
    with pytest.raises(ValueError, match=r"\.rrd"):
        LiveView(tmp_path / "live.mp4")
    with pytest.raises(ValueError, match="image_every"):
        LiveView(tmp_path / "live.rrd", image_every=0)


def test_without_a_display_the_view_goes_to_the_fallback_file(tmp_path, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    view = LiveView.for_display(tmp_path / "fallback.rrd")
    assert view.save == tmp_path / "fallback.rrd"
    assert view.close() == tmp_path / "fallback.rrd"
