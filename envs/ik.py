"""Inverse kinematics by damped least squares, for any simulator's arm.

A backend's kinematics supplies two functions of the arm joints, the pose error to the target
and the Jacobian at the last configuration the error was taken at, and :func:`solve_dls` does
the rest: ``dq = J^T (J J^T + damping^2 I)^-1 e``, steps capped at ``max_step`` rad, every
iterate clipped to the joint limits, and the best iterate (position error + 0.1 m/rad x
rotation error) returned when the target is out of reach, so the answer is always finite and
within limits. MuJoCo's (:mod:`rmb_lerobot.envs.mujoco.kinematics`) and PyBullet's
(:mod:`rmb_lerobot.envs.pybullet.kinematics`) arms use it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class IkResult:
    """Joint solution (arm joints only) and how far its pose is from the target."""

    qpos: np.ndarray
    converged: bool
    pos_error: float
    rot_error: float
    iterations: int


def solve_dls(
    error: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]],
    jacobian: Callable[[np.ndarray], np.ndarray],
    q_init: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    *,
    max_iters: int,
    pos_tol: float,
    rot_tol: float,
    damping: float,
    max_step: float,
) -> IkResult:
    """Damped least squares from ``q_init`` (clipped to the limits).

    Args:
        error: ``q -> (position error (3,), rotation vector error (3,))`` of the target
            relative to the pose at ``q``, both in one frame (it may set the model's state).
        jacobian: ``q -> (6, n)`` Jacobian at ``q`` in the frame of ``error``, called right
            after ``error(q)``.
        q_init: Starting joints (n,).
        lower: Joint lower limits (n,).
        upper: Joint upper limits (n,).
        max_iters: Iteration bound.
        pos_tol: Position tolerance (m) for convergence.
        rot_tol: Rotation tolerance (rad) for convergence.
        damping: Damping factor of the least squares.
        max_step: Largest joint change per iteration (rad).

    Returns:
        The converged solution, or the best iterate with ``converged=False``.
    """
    q = np.clip(q_init, lower, upper)
    regulariser = np.eye(6) * damping**2
    best = (np.inf, q.copy(), np.inf, np.inf)
    for iteration in range(max_iters + 1):
        pos_err, rot_err = error(q)
        p_norm, r_norm = float(np.linalg.norm(pos_err)), float(np.linalg.norm(rot_err))
        if p_norm + 0.1 * r_norm < best[0]:
            best = (p_norm + 0.1 * r_norm, q.copy(), p_norm, r_norm)
        if p_norm < pos_tol and r_norm < rot_tol:
            return IkResult(q.copy(), True, p_norm, r_norm, iteration)
        if iteration == max_iters:
            break
        jac = jacobian(q)
        dq = jac.T @ np.linalg.solve(jac @ jac.T + regulariser, np.concatenate([pos_err, rot_err]))
        largest = np.max(np.abs(dq))
        if largest > max_step:
            dq *= max_step / largest
        q = np.clip(q + dq, lower, upper)
    _, q_best, p_best, r_best = best
    return IkResult(q_best, False, p_best, r_best, max_iters)
