"""Subsample an episode like RMB's ``--skip``: keep every K-th step, keep relative keys honest.

RMB (``DataUtils.get_skipped_data_seq``) cuts a sequence into groups of K steps starting at
step 0 (the last group zero-padded) and keeps the first step of each group. A relative key holds
the change since the previous *recorded* step, so its group is aggregated instead: joint
differences are summed, relative eef poses composed (``rel_1 * rel_2 * ... * rel_K``). Unlike
RMB, which sums only joint and eef-pose differences, every relative key of the catalogue is
aggregated here (``*_gripper_joint_pos_rel`` too), so no relative key loses motion.
"""

from __future__ import annotations

import numpy as np

from rmb_lerobot import keys as K
from rmb_lerobot.pose import REL_POSE_DIM, matrix_to_rel_pose, rel_pose_to_matrix


def _groups(values: np.ndarray, skip: int) -> np.ndarray:
    """``(T, ...)`` -> ``(ceil(T / skip), skip, ...)``, zero-padded like RMB."""
    padding = (-len(values)) % skip
    if padding:
        values = np.concatenate([values, np.zeros((padding, *values.shape[1:]), values.dtype)])
    return values.reshape(-1, skip, *values.shape[1:])


def _compose_rel_poses(groups: np.ndarray) -> np.ndarray:
    """Compose each group's relative poses ``(N, skip, 6 * n)`` -> ``(N, 6 * n)``."""
    n, skip, dim = groups.shape
    rels = groups.reshape(n, skip, dim // REL_POSE_DIM, REL_POSE_DIM)
    total = rel_pose_to_matrix(rels[:, 0])
    for i in range(1, skip):
        total = total @ rel_pose_to_matrix(rels[:, i])
    return matrix_to_rel_pose(total).reshape(n, dim)


def skip_sequence(key: str, values: np.ndarray, skip: int) -> np.ndarray:
    """The ``(ceil(T / skip), ...)`` sequence RMB trains on for ``key`` with ``--skip skip``."""
    values = np.asarray(values)
    if skip < 1:
        raise ValueError(f"skip must be >= 1, got {skip}")
    if skip == 1:
        return values
    if not K.is_relative_key(key):
        return values[::skip]
    groups = _groups(values.astype(np.float64), skip)
    if K.spec(key).quantity is K.Quantity.EEF_POSE:
        return _compose_rel_poses(groups)
    return groups.sum(axis=1)
