"""Show an episode in the rerun viewer (RMB's VisualizeData, on rerun instead of matplotlib).

Logged on two timelines, ``step`` and ``time`` (seconds, from the ``time`` key):

* ``cameras/<camera>/rgb`` and ``cameras/<camera>/depth`` (metres) for every camera, under a
  ``cameras/<camera>`` pinhole made from the ``fovy`` attribute, so the 3D view shows each
  depth image as a point cloud (camera frame x right, y down, z forward, as
  :mod:`rmb_lerobot.pointcloud`);
* ``cameras/<camera>/pointcloud``: stored ``<camera>_pointcloud`` keys (xyz + rgb);
* ``plots/<key>``: every low-dimensional key (joints, eef poses, wrench, ...), one line per
  dimension;
* ``tactile/<key>``: every ``*_tactile_sensor`` key, as a tensor and, for 2-D grids, as a
  heat-map image scaled to the key's range over the episode;
* ``episode``: the attributes (task description, env, world) as text.

rerun is an optional dependency (the ``viz`` extra) imported only here.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
from tqdm import tqdm

from rmb_lerobot import keys as K
from rmb_lerobot.display import has_display, import_rerun
from rmb_lerobot.episode import Episode, open_episode
from rmb_lerobot.errors import RmbFormatError
from rmb_lerobot.staging import Staging

TACTILE_SUFFIX = "_tactile_sensor"
_CHUNK = 8  # frames per read and flush; 640x480, two cameras: 0.43 GB RSS (32: 0.84 GB)

_DIM_NAMES = {
    K.Quantity.EEF_POSE: ["tx", "ty", "tz", "qw", "qx", "qy", "qz"],
    K.Quantity.EEF_WRENCH: ["fx", "fy", "fz", "nx", "ny", "nz"],
    K.Quantity.EEF_VEL: ["vx", "vy", "vz", "wx", "wy", "wz"],
    K.Quantity.MOBILE_OMNI_VEL: ["vx", "vy", "wz"],
}
_REL_POSE_NAMES = ["tx", "ty", "tz", "roll", "pitch", "yaw"]
_JOINT_QUANTITIES = (K.Quantity.JOINT_POS, K.Quantity.JOINT_VEL, K.Quantity.JOINT_TORQUE)


def is_tactile_key(key: str) -> bool:
    return key.endswith(TACTILE_SUFFIX)


def _joint_names(layout: K.RobotLayout | None, dim: int) -> list[str] | None:
    """``joint0..joint5, gripper`` per arm (arm-prefixed when several), from the robot layout."""
    if layout is None or layout.num_joints != dim:
        return None
    groups = layout.arm_groups()
    names = [""] * dim
    for arm, (joints, grippers) in enumerate(groups):
        prefix = f"arm{arm}_" if len(groups) > 1 else ""
        for n, i in enumerate(joints):
            names[i] = f"{prefix}joint{n}"
        for n, i in enumerate(grippers):
            names[i] = f"{prefix}gripper{n if len(grippers) > 1 else ''}"
    return names


def _dim_names(key: str, dim: int, layout: K.RobotLayout | None = None) -> list[str]:
    spec = K.KEYS.get(key)
    base = None
    if spec is not None and spec.quantity is K.Quantity.EEF_POSE and spec.is_relative:
        base = _REL_POSE_NAMES
    elif spec is not None and spec.quantity in _JOINT_QUANTITIES:
        joints = _joint_names(layout, dim)
        if joints is not None:
            return joints
    elif spec is not None:
        base = _DIM_NAMES.get(spec.quantity)
    if base is not None and dim % len(base) == 0:
        arms = dim // len(base)
        return [f"{n}{i if arms > 1 else ''}" for i in range(arms) for n in base]
    return [f"{key}[{i}]" for i in range(dim)] if dim > 1 else [key]


def _heatmap(grid: np.ndarray, low: float, high: float) -> np.ndarray:
    scaled = (
        np.zeros(grid.shape, np.uint8)
        if high <= low
        else np.clip((grid - low) / (high - low) * 255, 0, 255).astype(np.uint8)
    )
    return cv2.cvtColor(cv2.applyColorMap(scaled, cv2.COLORMAP_VIRIDIS), cv2.COLOR_BGR2RGB)


def _log_episode(rr, rec, episode: Episode, stride: int, progress: bool) -> None:
    steps = np.arange(0, len(episode), stride)
    times = (
        np.asarray(episode[K.TIME][:], dtype=np.float64)[steps]
        if K.TIME in episode
        else steps.astype(np.float64)
    )
    attrs = "\n".join(f"- **{k}**: {v}" for k, v in episode.attrs.items())
    rec.log(
        "episode",
        rr.TextDocument(f"# {episode.path.name}\n\n{attrs}", media_type="text/markdown"),
        static=True,
    )

    def index():
        return [rr.TimeColumn("step", sequence=steps), rr.TimeColumn("time", duration=times)]

    layout = K.layout_for_env(episode.attrs.get(K.ATTR_ENV))
    image_keys, clouds, tactile = [], [], []
    for key in episode:
        if K.is_image_key(key):
            image_keys.append(key)
        elif K.is_pointcloud_key(key):
            clouds.append(key)
        elif is_tactile_key(key):
            tactile.append(key)
        elif key != K.TIME:
            values = np.asarray(episode[key][:], dtype=np.float64)[steps]
            values = values.reshape(len(steps), -1)
            rec.log(
                f"plots/{key}",
                rr.SeriesLines(names=_dim_names(key, values.shape[1], layout)),
                static=True,
            )
            rec.send_columns(
                f"plots/{key}", indexes=index(), columns=rr.Scalars.columns(scalars=values)
            )

    for camera in episode.camera_names:
        depth_key = K.depth_image_key(camera)
        if depth_key in episode and K.fovy_attr(camera) in episode.attrs:
            height, width = episode[depth_key].shape[1:3]
            fovy = np.deg2rad(episode.fovy(camera))
            pinhole = rr.Pinhole(
                fov_y=fovy,
                aspect_ratio=width / height,
                resolution=[width, height],
                camera_xyz=rr.ViewCoordinates.RDF,
            )
            rec.log(f"cameras/{camera}", pinhole, static=True)

    ranges = {key: _range(episode[key][:]) for key in tactile}
    series = {key: episode[key] for key in image_keys + clouds + tactile}  # one reader each
    bar = tqdm(
        total=len(steps), desc=f"view {episode.path.name}", unit="step", disable=not progress
    )
    with bar:
        for first in range(0, len(steps), _CHUNK):
            start = int(steps[first])
            window = slice(start, min(start + _CHUNK * stride, len(episode)), stride)
            frames = {key: series[key][window] for key in series}
            for j, i in enumerate(range(first, min(first + _CHUNK, len(steps)))):
                rec.set_time("step", sequence=int(steps[i]))
                rec.set_time("time", duration=float(times[i]))
                for key in image_keys:
                    image = frames[key][j]
                    if K.is_rgb_image_key(key):
                        rec.log(f"cameras/{K.camera_of(key)}/rgb", rr.Image(image))
                    else:
                        rec.log(
                            f"cameras/{K.camera_of(key)}/depth", rr.DepthImage(image, meter=1.0)
                        )
                for key in clouds:
                    cloud = np.asarray(frames[key][j])
                    colors = cloud[:, 3:6] if cloud.shape[-1] >= 6 else None
                    rec.log(
                        f"cameras/{K.camera_of(key)}/pointcloud",
                        rr.Points3D(cloud[:, :3], colors=colors),
                    )
                for key in tactile:
                    grid = np.asarray(frames[key][j], dtype=np.float32)
                    rec.log(f"tactile/{key}/values", rr.Tensor(grid))
                    if grid.ndim == 2:
                        rec.log(f"tactile/{key}/heatmap", rr.Image(_heatmap(grid, *ranges[key])))
                bar.update()
            rec.flush()  # hand each chunk to the sink now: bounds memory on long episodes


def _range(values: np.ndarray) -> tuple[float, float]:
    finite = np.asarray(values, dtype=np.float64)
    finite = finite[np.isfinite(finite)]
    return (float(finite.min()), float(finite.max())) if finite.size else (0.0, 0.0)


def view_episode(
    path: str | Path,
    *,
    save: str | Path | None = None,
    stride: int = 1,
    image_size: tuple[int, int] | None = None,
    spawn: bool | None = None,
    progress: bool = True,
) -> Path | None:
    """Log ``path`` to rerun: into the file ``save`` (an ``.rrd``), or a spawned viewer.

    Without ``save``, a viewer is spawned when a display exists (``spawn=None`` decides by
    :func:`has_display`), and otherwise the recording goes to ``<episode name>.rrd`` in the
    current directory. Returns the ``.rrd`` written, or None when only a viewer was fed.
    """
    rr = import_rerun("rmb-data view")
    if stride < 1:
        raise ValueError(f"stride must be >= 1, got {stride}")
    path = Path(path)
    if spawn is None:
        spawn = save is None and has_display()
    if save is None and not spawn:
        save = Path(path.name.rsplit(".", 1)[0] + ".rrd")
    if save is not None:
        save = Path(save)
        if save.suffix != ".rrd":
            raise RmbFormatError("the recording must be saved as a .rrd file", path=save)
    with open_episode(
        path, image_size=image_size, allow_non_finite=True, allow_missing_depth=True
    ) as episode:
        rec = rr.RecordingStream("rmb-data view", recording_id=str(path.resolve()))
        if save is None:
            rec.spawn()
            try:
                _log_episode(rr, rec, episode, stride, progress)
            finally:
                rec.flush()
                rec.disconnect()
            return None
        with Staging(save) as staging:  # an .rrd appears complete or not at all
            rec.save(staging.path)
            try:
                _log_episode(rr, rec, episode, stride, progress)
            finally:
                rec.flush()
                rec.disconnect()
            staging.commit(overwrite=True)
    return save
