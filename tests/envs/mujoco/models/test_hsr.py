"""RMB's Toyota HSR built from Toyota's published kinematics: names, home, limits, FK against
the hsrb4s URDF's joint origins, the planar base, the cameras and the hand."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from rmb_lerobot.envs.mujoco.kinematics import ArmKinematics
from rmb_lerobot.envs.mujoco.models.hsr import build_hsr
from rmb_lerobot.envs.mujoco.robots import MUJOCO_BUILDERS, check_model
from rmb_lerobot.envs.robots import HSR, GripperKind

# hsrb_description robots/hsrb4s.urdf.xacro (Toyota), joint limits.
URDF_LIMITS = {
    "arm_lift_joint": (0.0, 0.69),
    "arm_flex_joint": (-2.62, 0.0),
    "arm_roll_joint": (-2.09, 3.84),
    "wrist_flex_joint": (-1.92, 1.22),
    "wrist_roll_joint": (-1.92, 3.67),
    "hand_motor_joint": (-0.798, 1.24),
}


def compiled():
    model = build_hsr(HSR)
    return model, model.spec.compile()


def urdf_palm_pose(q: np.ndarray) -> tuple[np.ndarray, Rotation]:
    """``hand_palm_link`` in ``base_link`` from the URDF's joint origins, independently of the
    model: lift 0.34 m up and along z; flex at (0.141, 0.078, 0) about -y; roll 0.345 m up the
    flex link (0.005 m forward) about z; wrist flex about -y, wrist roll about z; the F/T frame
    and the wrist roll link (0.0735 m out and back, each turned by pi about x); the palm at
    (0.012, 0, 0.1405) turned by pi about z."""
    lift, flex, roll, wflex, wroll = q
    pos, rot = np.zeros(3), Rotation.identity()

    def move(offset, turn=None):
        nonlocal pos, rot
        pos = pos + rot.apply(offset)
        rot = rot if turn is None else rot * turn

    move([0, 0, 0.34 + lift])
    move([0.141, 0.078, 0], Rotation.from_rotvec([0, -flex, 0]))
    move([0.005, 0, 0.345], Rotation.from_rotvec([0, 0, roll]))
    move([0, 0, 0], Rotation.from_rotvec([0, -wflex, 0]))
    move([0, 0, 0], Rotation.from_rotvec([0, 0, wroll]))
    move([0, 0, 0.0735], Rotation.from_rotvec([np.pi, 0, 0]))
    move([0, 0, 0.0735], Rotation.from_rotvec([-np.pi, 0, 0]))
    move([0.012, 0, 0.1405], Rotation.from_rotvec([0, 0, np.pi]))
    return pos, rot


def test_names_home_limits_and_layout_are_rmbs():
    robot, model = compiled()
    check_model(HSR, robot, model)  # every name the record gives exists
    (arm,) = HSR.arms
    assert arm.joints == tuple(URDF_LIMITS)[:5]
    assert arm.home == (0.25, -2.0, 0.0, -1.0, 0.0) and arm.gripper.home_command == 0.8
    assert arm.gripper.kind is GripperKind.HAND and arm.gripper.joints == ("hand_motor_joint",)
    for name, limits in URDF_LIMITS.items():
        np.testing.assert_allclose(model.joint(name).range, limits)
        np.testing.assert_allclose(model.actuator(name).ctrlrange, limits)
    assert HSR.base.joints == ("mobile_x_joint", "mobile_y_joint", "mobile_theta_joint")
    for name in HSR.base.joints:  # RMB's velocity actuators, -1..1
        act = model.actuator(name)
        assert act.biasprm[2] == -act.gainprm[0] == -1000.0
        np.testing.assert_allclose(act.ctrlrange, (-1.0, 1.0))
    assert HSR.layout.num_joints == 6 and HSR.command_size == 9  # 5 + hand, then (vx, vy, wz)
    assert HSR.cameras == ("hand", "head") and robot.stand is None
    assert MUJOCO_BUILDERS["hsr"](HSR).name == "hsr"


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_palm_follows_the_urdf_joint_origins(seed):
    robot, model = compiled()
    kin = ArmKinematics(model, robot.arms[0])
    data = mujoco.MjData(model)
    rng = np.random.default_rng(seed)
    for _ in range(10):
        q = rng.uniform(kin.lower, kin.upper)
        data.qpos[kin.qpos_index] = q
        mujoco.mj_kinematics(model, data)
        pos, rot = urdf_palm_pose(q)
        palm = data.body("hand_palm_link")
        assert np.linalg.norm(palm.xpos - pos) < 1e-3
        np.testing.assert_allclose(palm.xmat.reshape(3, 3), rot.as_matrix(), atol=1e-6)


def test_home_points_the_hand_down_in_front_and_the_cameras_at_the_floor():
    robot, model = compiled()
    data = mujoco.MjData(model)
    robot.arms[0].set_home(model, data)
    tcp = data.site("hand_tcp")
    assert 0.4 < tcp.xpos[0] < 0.55 and 0.1 < tcp.xpos[2] < 0.35  # ahead, low
    hand_z = tcp.xmat.reshape(3, 3)[:, 2]
    assert hand_z @ [0, 0, -1] > 0.95  # fingers pointing (almost) down
    hand_view = -data.cam("hand").xmat.reshape(3, 3)[:, 2]  # cameras look along -z
    assert hand_view @ hand_z > 0.99
    head = data.cam("head")
    view = -head.xmat.reshape(3, 3)[:, 2]
    assert 0.9 < head.xpos[2] < 1.1  # on the head, about 1 m up
    np.testing.assert_allclose(np.degrees(np.arcsin(-view[2])), 45.0, atol=0.5)  # RMB's tilt
    assert view[0] > 0.7  # looking ahead
    assert model.cam("head").fovy[0] == model.cam("hand").fovy[0] == 62.0


def test_hand_command_opens_and_closes_both_fingers():
    robot, model = compiled()
    data = mujoco.MjData(model)
    robot.arms[0].set_home(model, data)
    reached = []
    for command in (1.24, -0.798, 0.8):
        data.actuator("hand_motor_joint").ctrl[0] = command
        mujoco.mj_step(model, data, nstep=250)
        motor = data.joint("hand_motor_joint").qpos[0]
        fingers = [data.joint(f"hand_{s}_proximal_joint").qpos[0] for s in "lr"]
        np.testing.assert_allclose(fingers, motor, atol=0.02)  # both follow the motor joint
        reached.append(motor)
    open_, closed, home = reached
    np.testing.assert_allclose([open_, home], [1.24, 0.8], atol=0.05)
    assert closed < -0.1  # closed until the fingertips press on each other
    pads = [g for g in range(model.ngeom) if "proximal" in model.body(model.geom_bodyid[g]).name]
    data.actuator("hand_motor_joint").ctrl[0] = -0.798
    mujoco.mj_step(model, data, nstep=250)
    touching = {
        frozenset((int(model.geom_bodyid[c.geom1]), int(model.geom_bodyid[c.geom2])))
        for c in data.contact[: data.ncon]
    }
    assert frozenset(int(model.geom_bodyid[g]) for g in pads) in touching
