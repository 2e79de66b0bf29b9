"""Checks of an episode's HDF5 file against the RMB format, from its header alone.

:func:`read_attrs` and :func:`dataset_names` turn whatever h5py raises on a damaged header into
:class:`RmbFormatError`; :func:`check_datasets` compares every dataset's dtype and shape with
the key catalogue (:mod:`rmb_lerobot.keys`) and the robot's layout. None of them reads data,
so opening an episode stays cheap. :func:`check_finite` checks values that were read; the
converter's float32 cast has its own check (:mod:`rmb_lerobot.converters.cast`).
"""

from __future__ import annotations

from collections.abc import Container, Iterable
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from rmb_lerobot import keys as K
from rmb_lerobot.errors import RmbFormatError

# Attributes the original RMB writes as one text string.
STRING_ATTRS = (K.ATTR_FORMAT, K.ATTR_DEMO_NAME, K.ATTR_TASK_DESC, K.ATTR_VERSION, K.ATTR_ENV)
# What h5py raises on a damaged header (and on names or values it cannot decode).
H5_ERRORS = (OSError, RuntimeError, KeyError, ValueError, TypeError, UnicodeError)


def _short(value: Any, limit: int = 80) -> str:
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


# ------------------------------------------------------------------ attributes
def read_attrs(h5: h5py.File, path: Path) -> dict[str, Any]:
    """Every root attribute, decoded: text as ``str``, name lists as ``list[str]``.

    Tolerates what the original RMB writes (fixed-length byte strings, empty name lists stored
    as empty float64 arrays); raises :class:`RmbFormatError` naming the attribute for
    unreadable values, text that is not UTF-8, and values of the wrong kind.
    """
    try:
        manager = h5.attrs
        names = list(manager.keys())
    except H5_ERRORS as exc:
        raise RmbFormatError(
            f"cannot list the file's attributes (corrupt HDF5 header?): {exc}", path=path
        ) from exc
    attrs = {}
    for name in names:
        try:
            value = manager[name]
        except H5_ERRORS as exc:
            raise RmbFormatError(
                f"cannot read attribute (corrupt HDF5 header?): {exc}", path=path, key=name
            ) from exc
        attrs[name] = _decode_attr(name, value, path)
    return attrs


def _text(name: str, value: Any, path: Path) -> str:
    """A str from h5py's str/bytes; invalid UTF-8 (h5py keeps it as surrogates) is an error."""
    try:
        text = value.decode("utf-8") if isinstance(value, bytes) else value
        text.encode("utf-8")
    except UnicodeError as exc:
        raise RmbFormatError(
            f"attribute holds bytes that are not UTF-8 text ({_short(value)}); expected UTF-8",
            path=path,
            key=name,
        ) from exc
    return text


def _decode_attr(name: str, value: Any, path: Path) -> Any:
    if name in K.STRING_LIST_ATTRS:
        return _name_list(name, value, path)
    if isinstance(value, str | bytes):
        return _text(name, value, path)
    if name in STRING_ATTRS:
        raise RmbFormatError(
            f"attribute holds {type(value).__name__} {_short(value)}; expected one text string",
            path=path,
            key=name,
        )
    if isinstance(value, np.ndarray) and value.dtype.kind in "OSU":
        return [_text(name, v, path) if isinstance(v, str | bytes) else str(v) for v in value]
    if isinstance(value, np.generic) and not isinstance(value, np.void):
        return value.item()
    return value


def _name_list(name: str, value: Any, path: Path) -> list[str]:
    if isinstance(value, np.ndarray) and value.size == 0:
        return []  # the original writes empty name lists as empty float64 arrays
    if isinstance(value, np.ndarray) and value.ndim == 1 and value.dtype.kind in "OSU":
        names = [v if isinstance(v, str | bytes) else None for v in value.tolist()]
        if None not in names:
            return [_text(name, v, path) for v in names]
    raise RmbFormatError(
        f"attribute holds {_short(value)}; expected a list of names (strings)",
        path=path,
        key=name,
    )


# ------------------------------------------------------------------ datasets
DatasetSpecs = dict[str, tuple[tuple[int, ...], np.dtype]]


def datasets(h5: h5py.File, path: Path) -> tuple[dict[str, h5py.h5d.DatasetID], DatasetSpecs]:
    """The root datasets by name (low-level ids), and their (shape, dtype).

    RMB files are flat (one dataset per key, no groups) and every key holds ``(T, ...)``.
    Reads object headers only, through h5py's low-level API: a high-level ``Dataset`` per key
    would cost 5 times more, and this is most of the cost of opening an episode.
    """
    try:
        names = list(h5.keys())
    except H5_ERRORS as exc:
        raise RmbFormatError(
            f"cannot list the file's datasets (corrupt header or names that are not UTF-8?): {exc}",
            path=path,
        ) from exc
    found: dict[str, h5py.h5d.DatasetID] = {}
    specs: DatasetSpecs = {}
    for name in names:
        if not isinstance(name, str):  # h5py returns names that are not UTF-8 as bytes
            raise RmbFormatError(
                "dataset name is not UTF-8 text; expected RMB key names",
                path=path,
                key=repr(name),
            )
        try:
            obj = h5py.h5o.open(h5.id, name.encode("utf-8"))
            is_dataset = isinstance(obj, h5py.h5d.DatasetID)
            shape, dtype = (obj.shape, obj.dtype) if is_dataset else (None, None)
        except H5_ERRORS as exc:
            raise _unopenable(h5, name, path, exc) from exc
        if not is_dataset:
            what = "a group" if isinstance(obj, h5py.h5g.GroupID) else type(obj).__name__
            raise RmbFormatError(
                f"found {what} where a dataset was expected; RMB files are flat: one dataset "
                "per key at the root",
                path=path,
                key=name,
            )
        if shape is None or len(shape) == 0:
            what = "no dataspace (empty)" if shape is None else f"a single value {shape}"
            raise RmbFormatError(
                f"dataset holds {what}; expected one row per step, shape (T, ...)",
                path=path,
                key=name,
            )
        found[name], specs[name] = obj, (shape, dtype)
    return found, specs


def _unopenable(h5: h5py.File, name: str, path: Path, exc: Exception) -> RmbFormatError:
    try:
        link = h5.get(name, getlink=True)
    except H5_ERRORS:
        link = None
    if isinstance(link, h5py.SoftLink | h5py.ExternalLink):
        target = link.path if isinstance(link, h5py.SoftLink) else f"{link.filename}:{link.path}"
        return RmbFormatError(
            f"dataset is a dangling link to {target!r}; expected a dataset", path=path, key=name
        )
    return RmbFormatError(f"cannot open dataset (corrupt HDF5 header?): {exc}", path=path, key=name)


_JOINT_QUANTITIES = (K.Quantity.JOINT_POS, K.Quantity.JOINT_VEL, K.Quantity.JOINT_TORQUE)


def _layout_field(quantity: K.Quantity) -> str | None:
    """The :class:`RobotLayout` field a quantity's size depends on."""
    if quantity in _JOINT_QUANTITIES:
        return "num_joints"
    if quantity is K.Quantity.GRIPPER_JOINT_POS:
        return "num_grippers"
    if quantity is K.Quantity.MOBILE_OMNI_VEL:
        return None
    return "num_eefs"


def infer_layout(specs: DatasetSpecs) -> tuple[K.RobotLayout, dict[str, str]]:
    """The layout the first key of each kind defines, for envs with no known robot.

    Returns the layout and, per layout field, the key it was taken from.
    """
    values: dict[str, int] = {}
    source: dict[str, str] = {}
    for name, spec in K.KEYS.items():
        if name not in specs or spec.quantity is None or len(specs[name][0]) != 2:
            continue
        field = _layout_field(spec.quantity)
        if field is None or field in values:
            continue
        size = specs[name][0][1]
        if field == "num_eefs":
            per_eef = spec.dim(K.RobotLayout(num_joints=0))
            if size % per_eef:
                continue
            size //= per_eef
        values[field], source[field] = size, name
    return K.RobotLayout(
        num_joints=values.get("num_joints", 0),
        num_grippers=values.get("num_grippers", 1),
        num_eefs=values.get("num_eefs", 1),
    ), source


def check_datasets(specs: DatasetSpecs, path: Path, env: Any = None) -> None:
    """Compare dtype and shape of every dataset with RMB's catalogue, from metadata only.

    ``specs`` maps dataset name to (shape, dtype). Low-dimensional keys must be float (reward:
    any number), ``(T,)`` for time/reward and ``(T, D)`` otherwise. When ``env`` names a known
    robot, ``D`` must be its layout's; otherwise the keys must agree with each other (measured
    and command, positions and velocities, absolute and relative). Images stored in HDF5 must
    be uint8 ``(T, H, W, 3)`` RGB and float ``(T, H, W)`` depth in metres.
    """
    layout = K.layout_for_env(env)
    source = None
    if layout is None:
        layout, source = infer_layout(specs)
    for name, (shape, dtype) in specs.items():
        if name in K.KEYS:
            _check_lowdim(name, shape, dtype, layout, env, source, path)
        elif K.is_image_key(name):
            _check_image(name, shape, dtype, path)


def _check_image(name: str, shape: tuple[int, ...], dtype: np.dtype, path: Path) -> None:
    if K.is_rgb_image_key(name):
        if dtype != np.uint8 or len(shape) != 4 or shape[3] != 3:
            raise RmbFormatError(
                f"RGB images are {dtype} {shape}; expected uint8 (T, H, W, 3)", path=path, key=name
            )
    elif dtype.kind != "f" or len(shape) != 3:
        hint = " (millimetres? RMB's HDF5 stores depth in metres)" if dtype.kind in "iu" else ""
        raise RmbFormatError(
            f"depth images are {dtype} {shape}{hint}; expected float metres (T, H, W)",
            path=path,
            key=name,
        )


def _check_lowdim(
    name: str,
    shape: tuple[int, ...],
    dtype: np.dtype,
    layout: K.RobotLayout,
    env: Any,
    source: dict[str, str] | None,
    path: Path,
) -> None:
    spec = K.KEYS[name]
    kinds = "fiub" if name == K.REWARD else "f"
    if dtype.kind not in kinds:
        raise RmbFormatError(
            f"holds {dtype} values; expected {'numbers' if name == K.REWARD else 'floats'}",
            path=path,
            key=name,
        )
    dim = spec.dim(layout)
    if dim == 0:
        if len(shape) == 1 or (len(shape) == 2 and shape[1] == 1):
            return
        raise RmbFormatError(f"has shape {shape}; expected (T,)", path=path, key=name)
    if len(shape) == 2 and shape[1] == dim:
        return
    got = f"{shape[1]} values per step" if len(shape) == 2 else f"shape {shape}"
    if source is None:
        why = (
            f"env {env!r} is a robot with {layout.num_joints} joint values "
            f"({layout.num_grippers} gripper(s), {layout.num_eefs} end effector(s)), for which "
            f"{name!r} holds {dim}"
        )
    else:
        definer = source.get(_layout_field(spec.quantity) or "", "RMB's definition")
        why = (
            f"as {definer!r} implies (env {env!r} names no known robot, so the keys must agree "
            "with each other: measured and command; positions, velocities and torques; "
            "absolute and relative)"
        )
    raise RmbFormatError(f"holds {got}; expected (T, {dim}), {why}", path=path, key=name)


# ------------------------------------------------------------------ values
def _steps_of(index: Any, length: int, rows: int) -> np.ndarray:
    """Step numbers of the rows a read returned (for error messages)."""
    if isinstance(index, slice):
        return np.arange(*index.indices(length))[:rows]
    if isinstance(index, int | np.integer):
        return np.array([int(index) % length])
    return np.asarray(index, dtype=np.int64).reshape(-1)[:rows] % max(length, 1)


def check_finite(data: np.ndarray, index: Any, length: int, path: Path, key: str) -> None:
    """Raise unless every value read is finite; names the first bad step and value."""
    finite = np.isfinite(data)
    if finite.all():
        return
    single = isinstance(index, int | np.integer)
    rows = 1 if single else len(data)
    bad = ~finite.reshape(rows, -1)
    row = int(np.flatnonzero(bad.any(axis=1))[0])
    value = data.reshape(rows, -1)[row][bad[row]][0]
    step = int(_steps_of(index, length, rows)[row])
    more = int(bad.sum()) - 1
    raise RmbFormatError(
        f"key {key!r} holds {value} at step {step}"
        f"{f' (and {more} more non-finite values in the steps read)' if more else ''}; "
        "RMB data must be finite (pass allow_non_finite=True to keep them)",
        path=path,
        key=key,
    )


def check_names_have_images(
    attrs: dict[str, Any], present: Container[str]
) -> list[tuple[str, str, str]]:
    """(attribute, camera, missing key) for every listed camera that lacks required images.

    RMB's recorder writes, for every step: RGB and depth of each camera in ``camera_names``,
    RGB of each sensor in ``rgb_tactile_names``, RGB and depth of each camera in
    ``pointcloud_camera_names`` (point clouds are computed from depth). RGB is required of
    every listed name. Depth is optional for ``camera_names`` (RMB's loader and policies read
    depth only when asked, and envs recording without depth are common) but required for
    ``pointcloud_camera_names``.
    """
    required = (
        (K.ATTR_CAMERA_NAMES, False),
        (K.ATTR_RGB_TACTILE_NAMES, False),
        (K.ATTR_POINTCLOUD_CAMERA_NAMES, True),
    )
    missing = []
    for attr, needs_depth in required:
        for camera in attrs.get(attr, []):
            wanted = [K.rgb_image_key(camera)]
            if needs_depth:
                wanted.append(K.depth_image_key(camera))
            missing += [(attr, camera, key) for key in wanted if key not in present]
    return missing


def check_finite_depth(data: np.ndarray, index: Any, length: int, path: Path, key: str) -> None:
    """Raise unless every depth pixel read is finite; names the first bad frame and counts.

    RMB's depth is finite metres with 0 for "no data" (its videos cannot even hold NaN), so a
    NaN or an infinity in an HDF5 depth image means a broken sensor or writer; before this
    check it reached a converted dataset as the near end of LeRobot's depth range.

    Args:
        data: Depth images as read, ``(H, W)`` for one frame or ``(N, H, W)``.
        index: The index they were read with (to name the frame).
        length: Frames in the episode.
        path: The HDF5 file, for the message.
        key: The depth key, for the message.

    Raises:
        RmbFormatError: Some pixel is NaN or infinite.
    """
    finite = np.isfinite(data)
    if finite.all():
        return
    single = isinstance(index, int | np.integer)
    rows = 1 if single else len(data)
    bad = (~finite).reshape(rows, -1).sum(axis=1)
    row = int(np.flatnonzero(bad)[0])
    frame = int(_steps_of(index, length, rows)[row])
    values = data.reshape(rows, -1)[row][~finite.reshape(rows, -1)[row]]
    kinds = ", ".join(sorted({"NaN" if np.isnan(v) else f"{v}" for v in values.tolist()}))
    frames = int(np.count_nonzero(bad))
    more = f"; {frames} of the frames read hold such pixels" if frames > 1 else ""
    raise RmbFormatError(
        f"depth frame {frame} holds {int(bad[row])} non-finite pixels ({kinds}){more}; RMB depth "
        "must be finite metres, 0 for no data (to keep them: allow_non_finite=True, "
        "--allow-non-finite)",
        path=path,
        key=key,
    )


def cameras_missing_depth(
    attrs: dict[str, Any], present: Container[str], recorded: Iterable[str] | None = None
) -> list[str]:
    """Depth keys of a compact episode whose video file was lost.

    With ``recorded`` (the file names of the ``video_sha256`` attribute: this package's
    writer lists every file it wrote), each recorded depth file must be there. Without it (the
    original RMB), RMB's recorder writes depth for every camera of ``camera_names`` or for none
    (an env records with or without depth): a listed camera lacking depth beside others that
    have it is a lost file, not a choice. (Episodes converted from LeRobot datasets may have
    depth for some cameras only; they carry ``recorded``.)

    Args:
        attrs: The episode's decoded attributes.
        present: The episode's keys.
        recorded: The video files the writer recorded, if it did.

    Returns:
        The depth keys missing, in ``camera_names`` (or file name) order.
    """
    if recorded is not None:
        stems = [name.split(".", 1)[0] for name in recorded]
        return [s for s in sorted(stems) if K.is_depth_image_key(s) and s not in present]
    cameras = attrs.get(K.ATTR_CAMERA_NAMES, [])
    wanted = [K.depth_image_key(camera) for camera in cameras]
    if not any(key in present for key in wanted):
        return []
    return [key for key in wanted if key not in present]
