"""DH forward kinematics for real-robot logs."""

import numpy as np
import pytest

from rmb_lerobot.kinematics import UR5E


def test_ur5e_zero_configuration_matches_the_published_geometry():
    # All joints at zero: the arm stretches along -x; the flange sits at
    # x = a2 + a3, y = -(d4 + d6), z = d1 - d5 (Universal Robots' DH conventions).
    transform = UR5E.transform(np.zeros(6))
    np.testing.assert_allclose(transform[:3, 3], [-0.8172, -0.2329, 0.0628], atol=1e-9)


def test_fk_is_an_episode_writer_callable_that_ignores_the_gripper_value():
    q = np.array([0.1, -1.2, 1.0, -0.5, 0.3, 0.2])
    with_gripper = np.concatenate([q, [255.0]])
    pose = UR5E(with_gripper)
    assert pose.shape == (7,)
    np.testing.assert_allclose(pose, UR5E(q))
    assert np.linalg.norm(pose[3:]) == pytest.approx(1.0)


def test_too_few_joints_is_an_error():
    with pytest.raises(ValueError, match="at least 6 joint values"):
        UR5E(np.zeros(5))
