"""Robot composition, FK from the MuJoCo model, and the damped-least-squares IK."""

import numpy as np
import pytest

from rmb_lerobot.envs.mujoco.kinematics import ArmKinematics
from rmb_lerobot.envs.mujoco.models.common import FORCE_SENSOR, TORQUE_SENSOR, ArmModel
from rmb_lerobot.envs.mujoco.robot import UR5E_2F85
from rmb_lerobot.envs.robots import UR5E as UR5E_RECORD
from rmb_lerobot.kinematics import UR5E
from rmb_lerobot.pose import quat_to_rotmat

ARM = UR5E_RECORD.arms[0]


@pytest.fixture(scope="module")
def kin(physics_env) -> ArmKinematics:
    return physics_env.sim.kinematics[0]


def test_composed_model_has_rmb_actuators_and_sensors(physics_env):
    model = physics_env.sim.model
    names = [model.actuator(i).name for i in range(model.nu)]
    assert names == [*UR5E_2F85.arm_actuators, UR5E_2F85.gripper_actuator]
    assert tuple(model.actuator_ctrlrange[-1]) == (0.0, 255.0)
    assert model.opt.timestep == pytest.approx(0.004)
    assert physics_env.measured_wrench().shape == (6,)


def test_fk_agrees_with_the_ur5e_dh_table(kin):
    rng = np.random.default_rng(0)
    for q in [np.array(ARM.home), *rng.uniform(-np.pi, np.pi, (5, 6))]:
        pose = kin.fk(q)
        dh = UR5E(q)
        # Menagerie's link lengths differ from the DH table by under a millimetre.
        assert np.linalg.norm(pose[:3] - dh[:3]) < 2e-3
        assert np.allclose(quat_to_rotmat(pose[3:]), quat_to_rotmat(dh[3:]), atol=1e-6)


def test_home_pose_points_the_gripper_down_over_the_table(physics_env, kin):
    physics_env.reset(seed=0)
    tcp = physics_env.sim.data.site(ARM.tcp_frame)
    assert tcp.xmat.reshape(3, 3)[:, 2] == pytest.approx([0, 0, -1], abs=1e-6)
    assert -0.3 < tcp.xpos[0] < 0.0 and tcp.xpos[2] > 0.9


def test_fk_ignores_the_gripper_value_and_rejects_short_input(kin):
    q = np.array(ARM.home)
    assert np.allclose(kin.fk(np.append(q, 255.0)), kin.fk(q))
    with pytest.raises(ValueError, match="at least 6"):
        kin.fk(q[:3])


def test_ik_recovers_fk_poses(kin):
    rng = np.random.default_rng(1)
    home = np.array(ARM.home)
    for _ in range(10):
        q_true = home + rng.normal(0.0, 0.3, 6)
        target = kin.fk(q_true)
        result = kin.ik(target, home)
        assert result.converged, result
        reached = kin.fk(result.qpos)
        assert np.linalg.norm(reached[:3] - target[:3]) < 1e-3
        assert abs(abs(np.dot(reached[3:], target[3:])) - 1.0) < 1e-6


def test_ik_respects_joint_limits_and_reports_unreachable_targets(kin):
    home = np.array(ARM.home)
    far = kin.fk(home)
    far[:3] = [3.0, 0.0, 0.5]  # far outside the ~0.85 m reach
    result = kin.ik(far, home)
    assert not result.converged and result.pos_error > 1.0
    assert np.all(result.qpos >= kin.lower) and np.all(result.qpos <= kin.upper)
    start = home.copy()
    start[2] = 5.0  # elbow beyond its +-pi limit: clipped before iterating
    assert kin.lower[2] <= kin.ik(kin.fk(home), start).qpos[2] <= kin.upper[2]


def test_ik_can_target_another_site(kin):
    home = np.array(ARM.home)
    target = kin.fk(home, site=ARM.tcp_frame)
    target[2] -= 0.05
    result = kin.ik(target, home, site=ARM.tcp_frame)
    assert result.converged
    assert kin.fk(result.qpos, site=ARM.tcp_frame)[:3] == pytest.approx(target[:3], abs=1e-3)
    with pytest.raises(ValueError, match="no site named"):
        kin.fk(home, site="nope")


def test_an_arm_model_needs_one_actuator_per_joint():
    with pytest.raises(ValueError, match="6 joints but 5 actuators"):
        ArmModel(
            record=ARM,
            arm_actuators=UR5E_2F85.arm_actuators[:5],
            gripper_actuator=UR5E_2F85.gripper_actuator,
            base_body=UR5E_2F85.arm_base_body,
            force_sensor=FORCE_SENSOR,
            torque_sensor=TORQUE_SENSOR,
            hand_camera="hand",
        )
