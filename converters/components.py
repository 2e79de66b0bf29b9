"""Per-dimension names of RMB keys, for the ``names`` of LeRobot features.

LeRobot stores one name per number of a vector feature; tools (the dataset viewer, GR00T's
``modality.json``, :mod:`.lerobot_to_rmb`) read them. Names say what each number is in RMB's
conventions, e.g. ``measured_joint_pos`` of a UR5e -> ``joint_0 ... joint_5, gripper``.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from rmb_lerobot import keys as K

_POSE = ("x", "y", "z", "qw", "qx", "qy", "qz")
_POLICY_POSE = ("x", "y", "z", "r00", "r01", "r02", "r10", "r11", "r12")  # position + 6-D rotation
_REL_POSE = ("x", "y", "z", "roll", "pitch", "yaw")
_TWIST = ("vx", "vy", "vz", "wx", "wy", "wz")
_WRENCH = ("fx", "fy", "fz", "nx", "ny", "nz")
_OMNI = ("vx", "vy", "wz")
_JOINT_QUANTITIES = (K.Quantity.JOINT_POS, K.Quantity.JOINT_VEL, K.Quantity.JOINT_TORQUE)


def infer_layout(dims: Mapping[str, int]) -> K.RobotLayout:
    """A robot's layout from the stored dimensions of an episode's keys.

    Joints come from a ``*_joint_pos``-like key, grippers from ``*_gripper_joint_pos`` (none if
    absent), end-effectors from ``*_eef_pose`` (7 numbers each) or its relative key (6 each).
    """

    def first(quantity: K.Quantity, relative: bool = False) -> int | None:
        for key, dim in dims.items():
            spec = K.KEYS.get(key)
            if spec is not None and spec.quantity is quantity and spec.is_relative == relative:
                return dim
        return None

    joints = next((d for q in _JOINT_QUANTITIES if (d := first(q)) is not None), 0)
    grippers = first(K.Quantity.GRIPPER_JOINT_POS) or 0
    eef_pose, eef_rel = first(K.Quantity.EEF_POSE), first(K.Quantity.EEF_POSE, relative=True)
    eefs = eef_pose // 7 if eef_pose else eef_rel // 6 if eef_rel else 1
    return K.RobotLayout(num_joints=joints, num_grippers=min(grippers, joints), num_eefs=eefs)


def _per_eef(names: tuple[str, ...], num_eefs: int) -> list[str]:
    if num_eefs == 1:
        return list(names)
    return [f"{name}_{i}" for i in range(num_eefs) for name in names]


def _grippers(count: int) -> list[str]:
    return ["gripper"] if count == 1 else [f"gripper_{i}" for i in range(count)]


def _joint_names(layout: K.RobotLayout) -> list[str]:
    """``joint_0 .. joint_5, gripper`` for one arm; per arm ``joint_<k>_<arm>, gripper_<arm>``
    in RMB's order (each arm's joints, then its gripper) for several."""
    groups = layout.arm_groups()
    if len(groups) == 1:
        joints, grippers = groups[0]
        return [f"joint_{k}" for k in range(len(joints))] + _grippers(len(grippers))
    return [
        name
        for arm, (joints, _) in enumerate(groups)
        for name in (*(f"joint_{k}_{arm}" for k in range(len(joints))), f"gripper_{arm}")
    ]


def component_names(key: str, dim: int, layout: K.RobotLayout, *, policy: bool) -> list[str]:
    """Names of the ``dim`` numbers ``key`` holds per step.

    ``policy`` selects the policy view of absolute eef poses (position + 6-D rotation). Keys
    whose size does not match the catalogue (another robot, an unknown key) get ``<key>_<i>``.
    """
    spec = K.KEYS.get(key)
    names: list[str] | None = None
    if spec is not None:
        if spec.quantity is None:
            names = [key]
        elif spec.quantity in _JOINT_QUANTITIES:
            names = _joint_names(layout)
        elif spec.quantity is K.Quantity.GRIPPER_JOINT_POS:
            names = _grippers(layout.num_grippers)
        elif spec.quantity is K.Quantity.EEF_POSE:
            single = _REL_POSE if spec.is_relative else _POLICY_POSE if policy else _POSE
            names = _per_eef(single, layout.num_eefs)
        elif spec.quantity is K.Quantity.EEF_VEL:
            names = _per_eef(_TWIST, layout.num_eefs)
        elif spec.quantity is K.Quantity.EEF_WRENCH:
            names = _per_eef(_WRENCH, layout.num_eefs)
        else:
            names = list(_OMNI)
    elif K.is_tactile_key(key):  # a fingertip grid, row-major: r<row>_c<column>
        rows, cols = K.TACTILE_SHAPE
        names = [f"r{i}_c{j}" for i in range(rows) for j in range(cols)]
    if names is None or len(names) != dim:
        names = [f"{key}_{i}" for i in range(dim)]
    return names


def split_by_prefix(names: list[str]) -> list[tuple[str, int]] | None:
    """``["measured_joint_pos.joint_0", ...]`` -> ``[("measured_joint_pos", 7), ...]``.

    The state/action names of a converted dataset are ``<rmb key>.<component>``; returns None
    when some name does not start with an RMB key (a dataset from another source).
    """
    groups: list[tuple[str, int]] = []
    for name in names:
        key = name.split(".", 1)[0]
        if key not in K.KEYS or "." not in name:
            return None
        if groups and groups[-1][0] == key:
            groups[-1] = (key, groups[-1][1] + 1)
        else:
            groups.append((key, 1))
    return groups


def stored_dim(values: np.ndarray) -> int:
    """Numbers per step of an episode array ``(T,)`` or ``(T, d...)``."""
    return int(np.prod(values.shape[1:], dtype=np.int64)) if values.ndim > 1 else 1
