"""Helpers for the robot model tests: a table like the UR5e scene's, settling, and a scripted
pick that lifts a cube 10 cm with the arm's own IK (physics invariants, not trajectories)."""

from __future__ import annotations

from collections.abc import Callable

import mujoco
import numpy as np
import pytest

from rmb_lerobot.envs.mujoco.kinematics import ArmKinematics
from rmb_lerobot.envs.mujoco.models.common import ArmModel, RobotModel
from rmb_lerobot.envs.workspace import RMB_TABLE

CUBE_HALF = 0.015  # a 3 cm cube of 50 g
CUBE_MASS = 0.05


def add_table(spec: mujoco.MjSpec) -> None:
    """The UR5e scene's table top (envs/mujoco/scene.py constants) and a floor."""
    spec.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 0.05])
    hx, hy = RMB_TABLE.table.half_size
    spec.worldbody.add_geom(
        name="table_top",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[hx, hy, 0.0075],
        pos=[0, 0, RMB_TABLE.table.top_z - 0.0075],
    )


def run_for(model: mujoco.MjModel, data: mujoco.MjData, seconds: float) -> None:
    for _ in range(round(seconds / model.opt.timestep)):
        mujoco.mj_step(model, data)


def tcp_down_pose(kin: ArmKinematics, data: mujoco.MjData, arm: ArmModel, pos) -> np.ndarray:
    """Root-frame pose putting the TCP at world ``pos``, tool axis straight down, keeping the
    current heading of the tool's x axis."""
    x = data.site(arm.tcp_site).xmat.reshape(3, 3)[:, 0].copy()
    x[2] = 0.0
    x /= np.linalg.norm(x)
    z = np.array([0.0, 0.0, -1.0])
    mat = np.column_stack([x, np.cross(z, x), z])
    return kin.world_to_root(np.asarray(pos, dtype=np.float64), mat)


def move_arm(model, data, arm: ArmModel, q_goal, seconds: float, hold: float = 0.3) -> None:
    """Ramp the arm servos' commands linearly to ``q_goal``, then hold."""
    ids = [model.actuator(name).id for name in arm.arm_actuators]
    q_start = data.ctrl[ids].copy()
    steps = round(seconds / model.opt.timestep)
    for i in range(1, steps + 1):
        data.ctrl[ids] = q_start + (np.asarray(q_goal) - q_start) * i / steps
        mujoco.mj_step(model, data)
    run_for(model, data, hold)


def pick_and_lift(
    robot: Callable[[], RobotModel],
    arm_index: int,
    offset_xy: tuple[float, float],
    yaw: float,
    grasp_depth: float,
) -> dict[str, float]:
    """Cube on the table below the arm's home TCP (shifted by ``offset_xy``, turned by
    ``yaw`` from the tool's heading); open, descend top-down until the TCP is ``grasp_depth``
    below the cube centre, close with a step command, lift the TCP 10 cm, hold 1 s.

    Returns the cube's rise, its drift relative to the TCP from closing to the end, and the
    measured gripper value while holding (in command units).
    """
    model_ = robot()
    arm = model_.arms[arm_index]
    spec = model_.spec
    add_table(spec)
    cube = spec.worldbody.add_body(name="cube", pos=[0, 0, 2])
    cube.add_freejoint()
    cube.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=[CUBE_HALF] * 3, mass=CUBE_MASS)
    model = spec.compile()
    data = mujoco.MjData(model)
    for other in model_.arms:
        other.set_home(model, data)
    kin = ArmKinematics(model, arm)  # reads arm_joints, root_body, eef_site
    tcp = data.site(arm.tcp_site).xpos.copy()
    heading = data.site(arm.tcp_site).xmat.reshape(3, 3)[:, 0]
    centre = np.array(
        [tcp[0] + offset_xy[0], tcp[1] + offset_xy[1], RMB_TABLE.table.top_z + CUBE_HALF]
    )
    cube_yaw = np.arctan2(heading[1], heading[0]) + yaw
    qadr = model.jnt_qposadr[model.body("cube").jntadr[0]]
    data.qpos[qadr : qadr + 3] = centre
    data.qpos[qadr + 3 : qadr + 7] = [np.cos(cube_yaw / 2), 0, 0, np.sin(cube_yaw / 2)]
    mujoco.mj_forward(model, data)
    run_for(model, data, 0.3)

    q = data.qpos[kin.qpos_index].copy()
    lo, hi = arm.gripper_ctrl_range
    open_cmd = arm.home_gripper
    close_cmd = hi if np.isclose(open_cmd, lo) else lo
    data.actuator(arm.gripper_actuator).ctrl[0] = open_cmd
    for height, seconds in ((0.10, 1.5), (-grasp_depth, 1.0)):
        target = tcp_down_pose(kin, data, arm, centre + np.array([0, 0, height]))
        solution = kin.ik(target, q, site=arm.tcp_site)
        assert solution.converged, f"IK failed for {model_.name} at height {height}"
        q = solution.qpos
        move_arm(model, data, arm, q, seconds)
    data.actuator(arm.gripper_actuator).ctrl[0] = close_cmd
    run_for(model, data, 0.8)
    cube_pos = data.body("cube").xpos
    start_rel = cube_pos - data.site(arm.tcp_site).xpos
    start_z = float(cube_pos[2])
    target = tcp_down_pose(kin, data, arm, data.site(arm.tcp_site).xpos + np.array([0, 0, 0.10]))
    solution = kin.ik(target, q, site=arm.tcp_site)
    assert solution.converged
    move_arm(model, data, arm, solution.qpos, 1.0, hold=1.0)
    drift = data.body("cube").xpos - data.site(arm.tcp_site).xpos - start_rel
    return {
        "rise": float(data.body("cube").xpos[2]) - start_z,
        "drift": float(np.linalg.norm(drift)),
        "gripper": arm.gripper_value(data),
        "finite": bool(np.all(np.isfinite(data.qpos))),
    }


@pytest.fixture
def pick():
    """``pick(build, arm_index, offset_xy, yaw, grasp_depth) -> dict`` (see pick_and_lift)."""
    return pick_and_lift


def gripper_sweep(robot: RobotModel, arm_index: int = 0, fractions=(0, 0.25, 0.5, 0.75, 1, 0)):
    """Measured gripper values (RMB's formula) after holding each command 1 s at home, with
    nothing between the fingers; commands are fractions of the command range."""
    model = robot.spec.compile()
    data = mujoco.MjData(model)
    for arm in robot.arms:
        arm.set_home(model, data)
    arm = robot.arms[arm_index]
    lo, hi = arm.gripper_ctrl_range
    values = []
    for fraction in fractions:
        data.actuator(arm.gripper_actuator).ctrl[0] = lo + fraction * (hi - lo)
        run_for(model, data, 1.0)
        values.append(arm.gripper_value(data))
    return np.array(values)


@pytest.fixture
def sweep():
    """``sweep(robot, arm_index=0, fractions=...) -> values`` (see gripper_sweep)."""
    return gripper_sweep


@pytest.fixture
def settle():
    """``settle(model, data, seconds)``: step the simulation."""
    return run_for


def compile_at_home(build: Callable[[], RobotModel]):
    """Build and compile a robot, every arm at its home pose: ``(robot, model, data)``."""
    robot = build()
    model = robot.spec.compile()
    data = mujoco.MjData(model)
    for arm in robot.arms:
        arm.set_home(model, data)
    return robot, model, data


@pytest.fixture
def at_home():
    """``at_home(build) -> (robot, model, data)``: compiled, every arm at home."""
    return compile_at_home
