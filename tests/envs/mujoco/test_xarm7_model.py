"""RMB's xArm7 model: names, home pose over the table, RMB's gripper convention, a grasp."""

from __future__ import annotations

import functools

import mujoco
import numpy as np
import pytest

from rmb_lerobot.envs.mujoco.models import xarm_gripper
from rmb_lerobot.envs.mujoco.models.common import rendered_mesh_faces
from rmb_lerobot.envs.mujoco.models.xarm7 import build_xarm7
from rmb_lerobot.envs.robots import XARM7, mounted
from rmb_lerobot.envs.workspace import RMB_TABLE

# RMB stands the xArm7 on its table, 0.22 m behind the centre (env_xarm7_cable.xml line 36).
ON_TABLE = (-0.22, 0.0, RMB_TABLE.table.top_z)
build = functools.partial(build_xarm7, mounted(XARM7, ON_TABLE))
HOME = XARM7.arms[0].home


def test_names_are_rmbs(at_home):
    robot, model, _ = at_home(build)
    arm = robot.arms[0]
    assert arm.arm_joints == tuple(f"joint{i}" for i in range(1, 8))
    assert arm.arm_actuators == tuple(f"act{i}" for i in range(1, 8))
    assert arm.home_arm_qpos == (0.0, 0.0, 0.0, 0.8, 0.0, 0.8, 0.0)
    assert (model.nq, model.nu, model.nsensor) == (7 + 6, 8, 2)
    actuators = [model.actuator(i).name for i in range(model.nu)]
    assert actuators == [*arm.arm_actuators, "gripper"]
    assert set(arm.gripper_joints) == {
        f"{side}_{joint}"
        for side in ("left", "right")
        for joint in ("driver_joint", "inner_knuckle_joint", "finger_joint")
    }
    assert robot.cameras == {"hand": "hand"} and model.camera("hand").id >= 0
    for name in (arm.eef_site, arm.tcp_site, arm.ft_site):
        assert model.site(name).id >= 0
    for sensor in (arm.force_sensor, arm.torque_sensor):
        assert model.sensor(sensor).objid[0] == model.site(arm.ft_site).id
    assert arm.gripper_ctrl_range == (0.0, 255.0) and arm.home_gripper == 0.0


def test_home_tcp_is_over_the_table_in_front_of_the_arm(at_home):
    robot, _, data = at_home(build)
    arm = robot.arms[0]
    tcp = data.site(arm.tcp_site).xpos
    hx, hy = RMB_TABLE.table.half_size
    assert ON_TABLE[0] < tcp[0] < hx and abs(tcp[1]) < hy
    assert RMB_TABLE.table.top_z + 0.05 < tcp[2] < RMB_TABLE.table.top_z + 0.3
    # Gripper pointing down at home, the hand camera looking the same way.
    tool_z = data.site(arm.tcp_site).xmat.reshape(3, 3)[:, 2]
    assert tool_z @ [0, 0, -1] > 0.99
    camera_view = -data.camera(arm.hand_camera).xmat.reshape(3, 3)[:, 2]
    assert camera_view @ tool_z > 0.99


def test_arm_holds_home_with_rmbs_gains(at_home, settle):
    robot, model, data = at_home(build)
    arm = robot.arms[0]
    settle(model, data, 2.0)
    q = np.array([data.joint(name).qpos[0] for name in arm.arm_joints])
    assert np.abs(q - HOME).max() < 0.03  # RMB's servos sag ~0.014 rad under gravity
    assert data.ncon == 0  # no self-contact at home


@pytest.mark.parametrize("joint", range(7))
def test_every_joint_follows_a_step_under_rmbs_gains(at_home, joint):
    """Each servo moves its joint 0.3 rad within 0.5 s (a force-limited servo on a light joint
    without armature chatters in place: RMB's wrist moved 5 mrad of a 0.5 rad step)."""
    robot, model, data = at_home(build)
    arm = robot.arms[0]
    target = HOME[joint] + 0.3
    data.actuator(arm.arm_actuators[joint]).ctrl[0] = target
    mujoco.mj_step(model, data, nstep=round(0.5 / model.opt.timestep))
    assert abs(data.joint(arm.arm_joints[joint]).qpos[0] - target) < 0.03  # gravity sag


def test_gripper_command_maps_to_rmbs_measured_value(sweep):
    values = sweep(build())
    # command 0, 63.75, 127.5, 191.25, 255, 0 -> mean(6 joints) / 0.8 * 255
    assert values[0] < 5 and values[-1] < 5
    assert abs(values[4] - 255) < 5
    assert np.all(np.diff(values[:5]) > 40)
    np.testing.assert_allclose(values[:5], [0, 63.75, 127.5, 191.25, 255], atol=5)


def test_the_six_gripper_joints_follow_the_driver(at_home, settle):
    robot, model, data = at_home(build)
    arm = robot.arms[0]
    for command in (0.0, 128.0, 255.0):
        data.actuator(arm.gripper_actuator).ctrl[0] = command
        settle(model, data, 1.0)
        q = [data.joint(name).qpos[0] for name in arm.gripper_joints]
        assert np.ptp(q) < 0.02, dict(zip(arm.gripper_joints, q, strict=True))


@pytest.mark.parametrize(
    ("offset_xy", "yaw"), [((0.0, 0.0), 0.0), ((0.03, -0.025), 0.25), ((-0.035, 0.03), -0.3)]
)
def test_holds_a_cube_lifted_10_cm(pick, offset_xy, yaw):
    # link_tcp is at the pads' tips: grasp with the TCP 1 cm below the cube centre.
    result = pick(build, 0, offset_xy, yaw, 0.01)
    assert result["finite"]
    assert result["rise"] > 0.08, result  # the arm lifts the TCP ~9 cm (servo sag)
    assert result["drift"] < 0.01, result  # the cube stays in the fingers
    assert 150 < result["gripper"] < 230, result  # closed on 3 cm, not empty (~255)


def test_visual_meshes_are_simplified_and_collision_meshes_kept():
    full = build(visual_mesh_error=0).spec.compile()
    light = build().spec.compile()
    assert rendered_mesh_faces(full) == 41096  # example-robot-data's 8 link meshes
    assert rendered_mesh_faces(light) < 12000  # the UR5e + 2F-85: ~17k
    hidden = [g for g in range(light.ngeom) if light.geom_group[g] == 3]
    assert all(light.geom_contype[g] for g in hidden if light.geom_type[g] == 7)
    np.testing.assert_array_equal(full.body_mass, light.body_mass)
    for model in (full, light):  # collision geoms: the same full meshes
        collision = [
            model.mesh_facenum[model.geom_dataid[g]]
            for g in range(model.ngeom)
            if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH and model.geom_contype[g]
        ]
        assert sum(collision) == 41096


def test_gripper_needs_a_radian_spec():
    spec = mujoco.MjSpec()  # compiler.degree defaults to True
    with pytest.raises(ValueError, match="degree"):
        xarm_gripper.add_xarm_gripper(spec, spec.worldbody, XARM7.arms[0].gripper, "tcp")
