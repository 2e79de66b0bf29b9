"""Driving a robot's mobile base in MuJoCo: velocity commands in, measured velocity out.

A :class:`~rmb_lerobot.envs.robots.MobileBase` moves on the floor through three planar joints
(x slide, y slide, yaw hinge, in the world frame), each driven by a velocity actuator. Commands
and measurements are in the base's own frame, as RMB's ``command_mobile_omni_vel`` and
``measured_mobile_omni_vel`` (``MujocoHsrEnvBase.convert_mobile_vel_frame``): a command
``(vx, vy, wz)`` is turned into the world frame at the base's current yaw when it is applied
(and held through the control step, as RMB does), the joints' world velocities are turned
back into the base frame when measured.
"""

from __future__ import annotations

import mujoco
import numpy as np

from rmb_lerobot.envs.robots import Robot


def yaw_rotation(yaw: float) -> np.ndarray:
    """The 2-D rotation by ``yaw`` (base frame -> world frame)."""
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, -s], [s, c]])


def pose_in_body(data: mujoco.MjData, body: str, pos: np.ndarray, rot: np.ndarray) -> np.ndarray:
    """A world position and rotation matrix as RMB's pose ``(x, y, z, qw, qx, qy, qz)`` in a
    body's current frame (a moving arm root on a mobile base)."""
    frame = data.body(body)
    mat = frame.xmat.reshape(3, 3)
    local = mat.T @ (np.asarray(pos, dtype=np.float64) - frame.xpos)
    quat = np.empty(4)
    local_mat = mat.T @ np.asarray(rot, dtype=np.float64).reshape(3, 3)
    mujoco.mju_mat2Quat(quat, np.ascontiguousarray(local_mat).reshape(9))
    return np.concatenate([local, quat])


class MobileBaseDrive:
    """The base's three joints and the velocity actuators driving them, in a compiled model.

    Args:
        model: The compiled scene.
        robot: A record with a base (:attr:`~rmb_lerobot.envs.robots.Robot.base`).

    Raises:
        ValueError: The record has no base, or the model lacks one of its joints, a joint is
            not the kind it should be (x, y slides, yaw hinge), or no actuator drives it.
    """

    def __init__(self, model: mujoco.MjModel, robot: Robot) -> None:
        if robot.base is None:
            raise ValueError(f"robot {robot.name!r} has no mobile base")
        kinds = (mujoco.mjtJoint.mjJNT_SLIDE,) * 2 + (mujoco.mjtJoint.mjJNT_HINGE,)
        qpos, dof, act = [], [], []
        for name, kind in zip(robot.base.joints, kinds, strict=True):
            joint = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)
            if joint < 0:
                raise ValueError(f"robot {robot.name!r}: the model has no base joint {name!r}")
            if model.jnt_type[joint] != kind:
                raise ValueError(
                    f"robot {robot.name!r}: base joint {name!r} must be a {kind.name}, the "
                    f"model's is {mujoco.mjtJoint(model.jnt_type[joint]).name}"
                )
            drives = [
                a
                for a in range(model.nu)
                if model.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_JOINT
                and model.actuator_trnid[a, 0] == joint
            ]
            if len(drives) != 1:
                raise ValueError(
                    f"robot {robot.name!r}: base joint {name!r} needs one actuator, has "
                    f"{len(drives)}"
                )
            qpos.append(model.jnt_qposadr[joint])
            dof.append(model.jnt_dofadr[joint])
            act.append(drives[0])
        self._qpos, self._dof, self._act = np.array(qpos), np.array(dof), np.array(act)

    def yaw(self, data: mujoco.MjData) -> float:
        """The base's yaw in the world (rad)."""
        return float(data.qpos[self._qpos[2]])

    def command(self, data: mujoco.MjData, velocity: np.ndarray) -> None:
        """Command ``(vx, vy, wz)`` in the base frame: the joints' world velocities at the
        current yaw."""
        velocity = np.asarray(velocity, dtype=np.float64)
        data.ctrl[self._act[:2]] = yaw_rotation(self.yaw(data)) @ velocity[:2]
        data.ctrl[self._act[2]] = velocity[2]

    def measured(self, data: mujoco.MjData) -> np.ndarray:
        """The base's velocity ``(vx, vy, wz)`` in its own frame."""
        world = data.qvel[self._dof]
        local = yaw_rotation(self.yaw(data)).T @ world[:2]
        return np.array([local[0], local[1], world[2]])
