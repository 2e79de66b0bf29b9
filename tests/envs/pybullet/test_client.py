"""The headless PyBullet client: RMB's physics settings, renderer choice, isolation, stepping."""

from __future__ import annotations

import gc
import math
import threading

import pybullet as p
import pytest

from rmb_lerobot.envs.pybullet import client as client_module
from rmb_lerobot.envs.pybullet.client import (
    PhysicsSettings,
    PybulletClient,
    connect,
    egl_unavailable_reason,
)


def _add_ball(client: PybulletClient, z: float = 1.0) -> int:
    """A 0.1 kg sphere at rest at height ``z``, without damping (so only gravity acts)."""
    shape = client.createCollisionShape(p.GEOM_SPHERE, radius=0.05)
    body = client.createMultiBody(0.1, shape, basePosition=(0.0, 0.0, z))
    client.changeDynamics(body, -1, linearDamping=0.0, angularDamping=0.0)
    return body


def test_rmb_settings() -> None:
    settings = PhysicsSettings()
    assert (settings.timestep, settings.substeps) == (0.005, 6)
    assert settings.control_dt == pytest.approx(0.03)
    assert settings.num_solver_iterations == 200
    assert settings.solver_residual_threshold == 1e-8
    assert (settings.enable_cone_friction, settings.gravity) == (1, -9.8)


@pytest.mark.parametrize(
    "kwargs", [{"timestep": 0.0}, {"substeps": 0}, {"substeps": 1.5}, {"enable_cone_friction": 2}]
)
def test_bad_settings_are_refused(kwargs: dict) -> None:
    with pytest.raises(ValueError):
        PhysicsSettings(**kwargs)


def test_connect_is_headless_direct_and_names_its_renderer() -> None:
    with connect(renderer="tiny") as client:
        assert client.renderer == "tiny"
        info = p.getConnectionInfo(physicsClientId=client.client_id)
        assert info == {"isConnected": 1, "connectionMethod": p.DIRECT}


def test_auto_picks_egl_when_it_works_else_warns_and_uses_tiny() -> None:
    reason = egl_unavailable_reason()
    if reason is None:
        with connect(renderer="auto") as client:
            assert client.renderer == "egl"
    else:
        with pytest.warns(RuntimeWarning, match="TinyRenderer"), connect() as client:
            assert client.renderer == "tiny"


def test_unknown_renderer_is_refused() -> None:
    with pytest.raises(ValueError, match="renderer"):
        connect(renderer="opengl")  # type: ignore[arg-type]


def test_settings_are_applied_and_survive_reset() -> None:
    settings = PhysicsSettings()
    with connect(settings, renderer="tiny") as client:
        for _ in range(2):  # once after connect, once after reset()
            params = client.getPhysicsEngineParameters()
            assert params["fixedTimeStep"] == pytest.approx(settings.timestep)
            assert params["numSolverIterations"] == settings.num_solver_iterations
            assert params["gravityAccelerationZ"] == pytest.approx(settings.gravity)
            client.reset()


def test_reset_empties_the_world() -> None:
    with connect(renderer="tiny") as client:
        client.loadURDF("plane.urdf")  # found through pybullet_data's search path
        assert client.getNumBodies() == 1
        client.reset()
        assert client.getNumBodies() == 0


def test_two_clients_are_independent() -> None:
    with connect(renderer="tiny") as a, connect(renderer="tiny") as b:
        assert a.client_id != b.client_id
        _add_ball(a)
        assert (a.getNumBodies(), b.getNumBodies()) == (1, 0)
        b.setGravity(0, 0, 0)
        assert a.getPhysicsEngineParameters()["gravityAccelerationZ"] == pytest.approx(-9.8)
        a.close()
        assert b.getNumBodies() == 0  # closing one leaves the other alone


def test_step_control_advances_six_substeps_of_5_ms() -> None:
    settings = PhysicsSettings()
    with connect(settings, renderer="tiny") as client:
        ball = _add_ball(client)
        client.step_control()
        (vx, vy, vz), _ = client.getBaseVelocity(ball)
        # Semi-implicit Euler: v = g * 6 * 0.005 exactly after one control step from rest.
        assert vz == pytest.approx(settings.gravity * settings.control_dt, abs=1e-9)
        assert math.hypot(vx, vy) < 1e-12
        (_, _, z), _ = client.getBasePositionAndOrientation(ball)
        # x_n = x_0 + g dt^2 n(n+1)/2 with n = 6 substeps
        assert z == pytest.approx(1.0 + settings.gravity * 0.005**2 * 21, abs=1e-9)


def test_close_is_idempotent_and_blocks_further_steps() -> None:
    client = connect(renderer="tiny")
    cid = client.client_id
    client.close()
    client.close()
    assert client.closed and not p.isConnected(physicsClientId=cid)
    with pytest.raises(RuntimeError, match="closed"):
        client.step_control()


def test_a_forgotten_client_is_disconnected_when_collected() -> None:
    cid = connect(renderer="tiny").client_id
    gc.collect()
    assert not p.isConnected(physicsClientId=cid)


def test_egl_client_and_one_egl_client_per_process() -> None:
    reason = egl_unavailable_reason()
    if reason is not None:
        pytest.skip(f"EGL unavailable: {reason}")
    with connect(renderer="egl") as first:
        assert first.renderer == "egl"
        # The plugin binds its GL context once, so a second EGL client would share it.
        with pytest.raises(RuntimeError, match="already uses the EGL plugin"):
            connect(renderer="egl")
        with pytest.warns(RuntimeWarning, match="already uses"), connect() as second:
            assert second.renderer == "tiny"
    with connect(renderer="egl") as again:  # the slot is free once the first one closed
        assert again.renderer == "egl"


def test_egl_still_renders_after_reset() -> None:
    """``reset()`` keeps the EGL plugin rendering. Without the plugin PyBullet silently draws
    ``ER_BULLET_HARDWARE_OPENGL`` with TinyRenderer, pixel for pixel, so an EGL image that
    differs from a TinyRenderer one of the same scene shows EGL is still in use."""
    reason = egl_unavailable_reason()
    if reason is not None:
        pytest.skip(f"EGL unavailable: {reason}")
    view = p.computeViewMatrixFromYawPitchRoll((0.5, 0, 0.05), 0.4, 90, -30, 0, 2)
    projection = p.computeProjectionMatrixFOV(60, 4 / 3, 0.01, 100)
    with connect(renderer="egl") as egl, connect(renderer="tiny") as tiny:
        egl.reset()
        images = []
        for client in (egl, tiny):
            client.loadURDF("plane.urdf")
            _add_ball(client, z=0.05)
            _, _, rgba, _, _ = client.getCameraImage(
                64, 48, view, projection, renderer=p.ER_BULLET_HARDWARE_OPENGL
            )
            images.append(bytes(rgba) if not hasattr(rgba, "tobytes") else rgba.tobytes())
        assert images[0] != images[1]


def _call_in_thread(function) -> BaseException | None:
    """Run ``function`` in a new thread; return what it raised, if anything."""
    raised: list[BaseException] = []

    def target() -> None:
        try:
            function()
        except BaseException as exc:  # handed back to the test
            raised.append(exc)

    thread = threading.Thread(target=target)
    thread.start()
    thread.join()
    return raised[0] if raised else None


def test_egl_refuses_to_render_from_another_thread() -> None:
    """EGL's context lives on the connecting thread; rendering elsewhere would segfault."""
    reason = egl_unavailable_reason()
    if reason is not None:
        pytest.skip(f"EGL unavailable: {reason}")
    with connect(renderer="egl") as client:
        raised = _call_in_thread(lambda: client.getCameraImage(8, 8))
        assert isinstance(raised, RuntimeError) and "thread" in str(raised)
        assert _call_in_thread(client.step_control) is None  # physics is not thread-bound
        client.getCameraImage(8, 8)  # the connecting thread still renders


def test_tiny_renders_from_any_thread() -> None:
    with connect(renderer="tiny") as client:
        assert _call_in_thread(lambda: client.getCameraImage(8, 8)) is None


def test_auto_falls_back_with_one_warning_naming_why(monkeypatch: pytest.MonkeyPatch) -> None:
    """The fallback path on every machine: pretend libEGL is missing."""
    missing = "no libEGL here"
    monkeypatch.setattr(client_module, "_libegl_failure", lambda: missing)
    with pytest.warns(RuntimeWarning, match=missing) as record, connect() as client:
        assert client.renderer == "tiny"
    assert len(record) == 1
    with pytest.raises(RuntimeError, match=missing):
        connect(renderer="egl")


def test_probe_reports_a_dying_plugin(monkeypatch: pytest.MonkeyPatch) -> None:
    """The plugin exits its process on EGL errors; the child probe turns that into a reason."""
    dying = "import sys; print('failed to EGL with glad.', file=sys.stderr); sys.exit(1)"
    monkeypatch.setattr(client_module, "_PROBE_SOURCE", dying)
    reason = client_module._egl_probe_failure.__wrapped__("unused")
    assert "exit code 1" in reason and "failed to EGL with glad." in reason
