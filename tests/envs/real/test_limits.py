"""Per-robot limits: joint names from the robot records, numbers from RMB's real envs."""

from __future__ import annotations

import numpy as np
import pytest

from rmb_lerobot.envs.real.limits import SafetyLimits, WorkspaceBox, limits_for, ur5e_tcp_fk
from rmb_lerobot.envs.robots import UR5E, UR5E_DUAL, XARM7
from rmb_lerobot.kinematics import UR5E as UR5E_DH


def test_ur5e_numbers_are_rmbs():
    lim = limits_for("ur5e")
    assert lim.joints == UR5E.arms[0].joints
    assert np.rad2deg(lim.v_lim) == pytest.approx(191.0)
    # +-2 pi everywhere but the elbow (index 2), +-pi.
    np.testing.assert_allclose(lim.high, [2 * np.pi, 2 * np.pi, np.pi, *[2 * np.pi] * 3])
    np.testing.assert_allclose(lim.low, -np.asarray(lim.high))
    assert lim.gripper == (0.0, 255.0)
    assert (lim.step_scale, lim.reset_scale) == (2.0, 0.3)
    assert np.rad2deg(lim.jump_threshold) == pytest.approx(90.0)
    assert (lim.jump_min_duration, lim.reset_duration_range) == (0.1, (0.1, 10.0))
    assert lim.scale_range == (0.01, 10.0)
    assert lim.watchdog_timeout == 0.2
    assert lim.workspace is None


def test_xarm7_numbers_are_rmbs():
    lim = limits_for("xarm7")
    assert lim.joints == XARM7.arms[0].joints == tuple(f"joint{i}" for i in range(1, 8))
    assert np.rad2deg(lim.v_lim) == pytest.approx(180.0)
    np.testing.assert_allclose(np.rad2deg(lim.low), [-360, -118, -360, -11, -360, -97, -360])
    np.testing.assert_allclose(np.rad2deg(lim.high), [360, 120, 360, 225, 360, 180, 360])
    assert lim.reset_scale == 0.1
    # Our record's 0 (open)..255 (closed); the xArm driver maps it to the SDK's 840..0 pulses.
    assert lim.gripper == XARM7.arms[0].gripper.command_range == (0.0, 255.0)
    assert limits_for("xarm7", gripper=(10.0, 200.0)).gripper == (10.0, 200.0)


def test_dual_ur5e_has_one_limits_per_arm():
    left, right = limits_for("ur5e_dual", arm=0), limits_for("ur5e_dual", arm=1)
    assert left.joints[0] == "left/shoulder_pan_joint"
    assert right.joints == UR5E_DUAL.arms[1].joints
    assert left.high == right.high == limits_for("ur5e").high
    with pytest.raises(IndexError, match="no arm 2"):
        limits_for("ur5e_dual", arm=2)


def test_unknown_robot_names_the_known_ones():
    with pytest.raises(KeyError, match=r"panda.*known"):
        limits_for("panda")


@pytest.mark.parametrize(
    "change, match",
    [
        ({"low": (-1.0, 2.0)}, "joint b bounds 2.0 >= 1.0"),
        ({"v_lim": 0.0}, "v_lim must be > 0"),
        ({"v_lim": float("nan")}, "finite"),
        ({"gripper": (255.0, 0.0)}, "gripper needs low < high"),
        ({"high": (1.0,)}, "2 joints but 2 low and 1 high"),
        ({"max_stale_reads": 0}, "max_stale_reads"),
    ],
)
def test_limits_refuse_nonsense(change, match):
    base = dict(
        robot="toy", joints=("a", "b"), low=(-1.0, -1.0), high=(1.0, 1.0), v_lim=1.0,
        gripper=(0.0, 255.0), reset_scale=0.3,
    )  # fmt: skip
    with pytest.raises(ValueError, match=match):
        SafetyLimits(**{**base, **change})


def test_workspace_box_distance():
    box = WorkspaceBox((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), fk=lambda q: q[:3])
    assert box.distance(np.array([0.5, 0.5, 0.5])) == 0.0
    assert box.distance(np.array([1.0, 1.0, 1.0])) == 0.0  # the faces count as inside
    assert box.distance(np.array([1.3, 0.5, -0.4])) == pytest.approx(0.5)  # 3-4-5
    with pytest.raises(ValueError, match="low < high"):
        WorkspaceBox((0.0, 0.0, 1.0), (1.0, 1.0, 1.0), fk=lambda q: q)


def test_ur5e_tcp_fk_is_the_dh_flange_plus_the_tool():
    q = np.array([0.3, -1.2, 1.1, -1.4, -1.5, 0.2])
    flange = UR5E_DH.transform(q)
    np.testing.assert_allclose(ur5e_tcp_fk()(q), flange[:3, 3])
    np.testing.assert_allclose(ur5e_tcp_fk(0.15)(q), flange[:3, 3] + 0.15 * flange[:3, 2])
