"""Play a recording backwards: the algebra SART needs for every RMB key.

SART records the robot driving *away* from a point of the demonstration and plays that
recording backwards, which yields a trajectory that *converges* onto the demonstration. Every
key of an RMB episode has to be reversed in the way its meaning dictates:

* absolute measured values (joint positions, gripper, eef poses, wrench, torque), reward and
  images: the same values in reverse order;
* measured velocities (``*_joint_vel``, ``*_eef_vel``, ``*_mobile_omni_vel``): reverse order
  and negated (moving backwards in time flips every velocity);
* relative keys (``*_rel``: RMB's "difference from the previous step", the first step zero):
  step ``s`` of the reversed recording differs from step ``s - 1`` by the *inverse* of the
  forward difference that led from the same two states, i.e. ``-d[T - s]`` for joint and
  gripper positions and ``inverse(rel[T - s])`` for the eef pose (a rigid transform), with
  step 0 zero again. This is exactly what recomputing the differences from the reversed
  absolute values gives (tested). RMB's own ``DataManager.reverse_data`` negates and inverts
  ``rel[T - 1 - s]`` instead, one step off;
* commands (``command_*``): a command leads the state it produces. Forward, the command sent at
  step ``t`` is reached about ``lag`` steps later; played backwards the same pairing needs the
  command ``2 * lag`` steps further along the reversed recording, so command keys are reversed
  and then advanced by ``command_shift`` steps (held at the last value where they run out:
  :class:`~rmb_lerobot.augment.sart.Augmenter` replaces those frames with the demo's own
  commands when it joins the reversed motion to the demo).
  ``command_joint_vel`` is ``(command[t] - command[t-1]) / dt`` in RMB's simulated recorders, so
  it is reversed like a relative key; velocity commands (``command_eef_vel``,
  ``command_mobile_omni_vel``) are instantaneous and reversed like measured velocities;
* ``time``: left as recorded (ascending); the caller renumbers the assembled episode.

A key with no rule is refused, naming it: a silent wrong reversal would corrupt training data.
"""

from __future__ import annotations

from collections.abc import Mapping
from enum import Enum

import numpy as np

from rmb_lerobot import keys as K
from rmb_lerobot.errors import RmbFormatError
from rmb_lerobot.pose import (
    REL_POSE_DIM,
    matrix_to_rel_pose,
    rel_pose_to_matrix,
    relative_pose_sequence,
)

__all__ = [
    "Rule",
    "derive_relative",
    "invert_rel_pose",
    "reversal_rule",
    "reverse_recording",
    "reverse_relative",
]

_VELOCITIES = (K.Quantity.JOINT_VEL, K.Quantity.EEF_VEL, K.Quantity.MOBILE_OMNI_VEL)


class Rule(Enum):
    """How one key is played backwards."""

    KEEP = "keep"  # time: left as recorded
    REVERSE = "reverse"  # absolute values, images, reward
    NEGATE = "negate"  # instantaneous velocities
    DIFFERENCE = "difference"  # per-step differences (joint/gripper *_rel, command_joint_vel)
    REL_POSE = "rel_pose"  # per-step rigid transforms (*_eef_pose_rel)


def reversal_rule(key: str) -> tuple[Rule, bool]:
    """How ``key`` is reversed, and whether it is a command (advanced by ``command_shift``)."""
    if key == K.TIME:
        return Rule.KEEP, False
    if key == K.REWARD or K.is_image_key(key) or K.is_pointcloud_key(key):
        return Rule.REVERSE, False
    spec = K.KEYS.get(key)
    if spec is None:
        raise RmbFormatError(
            "no reversal rule for this key (known: RMB's low-dimensional keys, time, reward and "
            "camera keys)",
            key=key,
        )
    command = spec.source == K.COMMAND
    if spec.is_relative:
        return (Rule.REL_POSE if spec.quantity is K.Quantity.EEF_POSE else Rule.DIFFERENCE), command
    if spec.quantity is K.Quantity.JOINT_VEL and command:
        return Rule.DIFFERENCE, True  # (command[t] - command[t-1]) / dt
    if spec.quantity in _VELOCITIES:
        return Rule.NEGATE, command
    return Rule.REVERSE, command


def invert_rel_pose(rel: np.ndarray) -> np.ndarray:
    """Inverse rigid transforms of RMB relative poses ``(..., 6k)`` (k eefs side by side)."""
    rel = np.asarray(rel, dtype=np.float64)
    if rel.shape[-1] % REL_POSE_DIM:
        raise ValueError(f"relative poses need a multiple of 6 numbers, got shape {rel.shape}")
    per_eef = rel.reshape(*rel.shape[:-1], -1, REL_POSE_DIM)
    inverse = matrix_to_rel_pose(np.linalg.inv(rel_pose_to_matrix(per_eef)))
    return inverse.reshape(rel.shape)


def _reversed_index(length: int, shift: int) -> np.ndarray:
    """Index of the forward step each reversed step takes its value from (held at step 0)."""
    return np.clip(length - 1 - np.arange(length) - shift, 0, length - 1)


def reverse_relative(rel: np.ndarray, *, pose: bool, shift: int = 0) -> np.ndarray:
    """Per-step differences of a recording played backwards (and advanced by ``shift``).

    ``rel[t]`` takes step ``t - 1`` to step ``t`` (``rel[0]`` is zero). Played backwards, step
    ``s`` comes from forward step ``j = T - 1 - s - shift`` and the one before it from
    ``j + 1``, so the difference is the inverse of ``rel[j + 1]``: negated for joint values,
    the inverse transform for eef poses (``pose=True``); zero where no forward step is left and
    at step 0.
    """
    rel = np.asarray(rel)
    length = len(rel)
    out = np.zeros_like(rel, dtype=np.float64)
    source = length - np.arange(length) - shift  # j + 1
    valid = (source >= 1) & (source <= length - 1)
    valid[0] = False
    picked = rel[source[valid]]
    if len(picked):
        out[valid] = invert_rel_pose(picked) if pose else -picked
    return out.astype(rel.dtype, copy=False)


def reverse_recording(
    data: Mapping[str, np.ndarray], *, command_shift: int = 0
) -> dict[str, np.ndarray]:
    """Every key of a recording (step-major arrays) played backwards; see the module docs.

    ``command_shift`` advances command keys by that many steps (``2 * lag`` for a controller
    that reaches a command ``lag`` steps after it is sent; 0 keeps RMB's pairing).
    """
    if command_shift < 0:
        raise ValueError(f"command_shift must be >= 0, got {command_shift}")
    lengths = {key: len(value) for key, value in data.items()}
    if len(set(lengths.values())) > 1:
        raise RmbFormatError(f"keys have different lengths: {lengths}")
    out: dict[str, np.ndarray] = {}
    for key, value in data.items():
        value = np.asarray(value)
        rule, command = reversal_rule(key)
        shift = command_shift if command else 0
        if rule is Rule.KEEP:
            out[key] = value.copy()
        elif rule in (Rule.DIFFERENCE, Rule.REL_POSE):
            out[key] = reverse_relative(value, pose=rule is Rule.REL_POSE, shift=shift)
        else:
            reversed_ = value[_reversed_index(len(value), shift)]
            out[key] = -reversed_ if rule is Rule.NEGATE else reversed_
    return out


def derive_relative(data: Mapping[str, np.ndarray], keys: set[str] | None = None) -> dict:
    """The ``_rel`` keys of the absolute keys in ``data`` (RMB's definition: difference from
    the previous step, the first step zero; eef poses ``prev^-1 * current`` per eef), limited
    to ``keys`` when given."""
    derived = {}
    for key, values in data.items():
        spec = K.KEYS.get(key)
        if spec is None or spec.is_relative or spec.quantity not in K.RELATIVE_QUANTITIES:
            continue
        rel = K.rel_key(key)
        if keys is not None and rel not in keys:
            continue
        values = np.asarray(values, dtype=np.float64)
        if spec.quantity is K.Quantity.EEF_POSE:
            poses = values.reshape(len(values), -1, 7)
            rels = np.stack([relative_pose_sequence(poses[:, i]) for i in range(poses.shape[1])], 1)
            derived[rel] = rels.reshape(len(values), -1)
        else:
            diff = np.zeros_like(values)
            diff[1:] = values[1:] - values[:-1]
            derived[rel] = diff
    return derived
