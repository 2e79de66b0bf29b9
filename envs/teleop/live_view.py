"""The teleoperation live view: what the operator drives, in rerun, as it happens.

After each control step the session hands itself to :meth:`LiveView.log_step`, which logs on
the ``step`` timeline:

* ``cameras/<camera>/rgb``: env 0's camera images (every ``image_every``-th step);
* ``tactile/<sensor>``: its fingertip tactile images, where the env has them;
* ``eef_target/arm<i>``: each arm's end-effector target ``(x, y, z, qw, qx, qy, qz)`` in the
  arm's root frame (what the device drives and IK solves for), one line per value;
* ``phase``: the phase, as a text log entry whenever it changes;
* ``success/env<k>``: 1 once env ``k``'s task has succeeded (one line per parallel env).

A viewer window is spawned when a display exists; otherwise the recording goes to an ``.rrd``
file, built in a hidden temporary and moved into place on :meth:`LiveView.close` (open it later
with ``rerun FILE.rrd``). rerun is an optional dependency (the ``viz`` extra), imported here
only when a live view is asked for.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from rmb_lerobot.display import has_display, import_rerun
from rmb_lerobot.staging import Staging

if TYPE_CHECKING:
    from rmb_lerobot.envs.teleop.session import TeleopSession

_POSE_NAMES = ["x", "y", "z", "qw", "qx", "qy", "qz"]


class LiveView:
    """A rerun recording of a teleoperation session.

    Args:
        save: The ``.rrd`` file to write; None: spawn a viewer window.
        image_every: Log images every this many steps (1: every step); images dominate the
            view's cost.
        app_id: The rerun application id.

    Raises:
        ImportError: rerun is not installed.
        ValueError: ``save`` does not end in ``.rrd``, or ``image_every`` < 1.
    """

    def __init__(self, save: Path | None, *, image_every: int = 1, app_id: str = "rmb-teleop"):
        if save is not None and Path(save).suffix != ".rrd":
            raise ValueError(f"--live-view {save}: the recording must be a .rrd file")
        if image_every < 1:
            raise ValueError(f"image_every must be >= 1, got {image_every}")
        self.rr = import_rerun("--live-view")
        self.save = None if save is None else Path(save)
        self.image_every = image_every
        self.rec = self.rr.RecordingStream(app_id)
        self._staging: Staging | None = None
        if self.save is None:
            self.rec.spawn()
        else:
            self.save.parent.mkdir(parents=True, exist_ok=True)
            self._staging = Staging(self.save)
            self.rec.save(self._staging.path)
        self._phase: str | None = None
        self._series_logged = False

    @classmethod
    def for_display(cls, fallback: Path, **kwargs: Any) -> LiveView:
        """A viewer window when a display exists, else a recording saved to ``fallback``."""
        return cls(None if has_display() else fallback, **kwargs)

    def log_step(self, session: TeleopSession) -> None:
        """Log the session's state after its last step (env 0's images, the targets, the phase,
        each env's success)."""
        rr, rec = self.rr, self.rec
        step = session.result.steps
        rec.set_time("step", sequence=step)
        if not self._series_logged:
            self._log_series_names(session)
        phase = str(session.phase)
        if phase != self._phase:
            rec.log("phase", rr.TextLog(f"{phase}{' (recording)' if session.recording else ''}"))
            self._phase = phase
        lane = session.lanes[0]
        if (step - 1) % self.image_every == 0:
            pixels = lane.obs.get("pixels", {}) if lane.obs else {}
            tactile = set(lane.env.tactile_names)
            for name, image in pixels.items():
                path = f"tactile/{name}" if name in tactile else f"cameras/{name}/rgb"
                rec.log(path, rr.Image(image))
        if session.tracker is not None:
            for arm in range(len(session.tracker.targets)):
                pose = session.tracker.target_pose(arm)
                rec.log(f"eef_target/arm{arm}", rr.Scalars(pose))
        for other in session.lanes:
            rec.log(f"success/env{other.index}", rr.Scalars(float(other.success)))

    def _log_series_names(self, session: TeleopSession) -> None:
        rr, rec = self.rr, self.rec
        arms = len(session.env.robot.arms)
        for arm in range(arms):
            rec.log(f"eef_target/arm{arm}", rr.SeriesLines(names=_POSE_NAMES), static=True)
        self._series_logged = True

    def close(self) -> Path | None:
        """Flush the recording; an ``.rrd`` is moved into place (also after Ctrl-C: every step
        logged so far is in it). Returns the file written, or None for a viewer."""
        self.rec.flush()
        self.rec.disconnect()
        if self._staging is None:
            return None
        staging, self._staging = self._staging, None
        return staging.commit(overwrite=True)
