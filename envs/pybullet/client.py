"""A headless PyBullet client with RoboManipBaselines' TACTO physics settings.

RMB's TACTO Sawyer envs open a ``p.GUI`` client (``RMB: envs/tacto/TactoSawyerEnvBase.py:101``);
without an X server that exits the whole process (no Python exception), so this module always
connects in ``p.DIRECT`` mode and renders offscreen, through PyBullet's EGL renderer plugin when
it works here, else through its built-in software TinyRenderer.

Every call passes ``physicsClientId`` explicitly (as ``pybullet_utils.bullet_client`` does), so
several clients in one process never touch each other or PyBullet's implicit default client.

Found while building this (pybullet 3.2.7), all of which would otherwise end or corrupt the
process with no Python exception:

- The EGL plugin ``exit(1)``s when EGL is unusable, so :func:`connect` probes it in a child
  process first. On a GPU machine whose image had NVIDIA's ``libEGL_nvidia`` but no libglvnd
  ``libEGL.so.1`` it failed ("failed to EGL with glad."); with ``libEGL.so.1`` added it
  rendered on the GPU (``GL_RENDERER=NVIDIA H200/PCIe/SSE2``).
- With the EGL plugin, creating a body whose visual is ``GEOM_PLANE`` (or a collision-only
  ``GEOM_PLANE`` body, whose visual PyBullet derives from it) segfaults: build floors as
  thin boxes or load ``plane.urdf`` (a mesh).
- Two EGL clients in one process draw into each other's GL context (the plugin makes its
  context current once, when loaded): the second EGL client is refused ("egl") or falls
  back to TinyRenderer ("auto").
- Rendering an EGL client from a thread other than the one that connected it segfaults:
  :meth:`PybulletClient.check_render_thread` raises instead.

Example:
    >>> from rmb_lerobot.envs.pybullet.client import PhysicsSettings, connect
    >>> with connect(PhysicsSettings(), renderer="tiny") as client:
    ...     body = client.loadURDF("plane.urdf")
    ...     client.step_control()  # 6 x 0.005 s
"""

from __future__ import annotations

import ctypes
import functools
import importlib.util
import inspect
import logging
import subprocess
import sys
import threading
import warnings
import weakref
from dataclasses import dataclass
from typing import Any, Literal

import pybullet as p
import pybullet_data

logger = logging.getLogger(__name__)

Renderer = Literal["auto", "egl", "tiny"]
"""What :func:`connect` is asked for: ``"auto"`` is EGL when it works here, else TinyRenderer."""

RENDERERS: tuple[str, ...] = ("auto", "egl", "tiny")

_EGL_MODULE = "eglRenderer"
_EGL_PLUGIN_SUFFIX = "_eglRendererPlugin"
_PROBE_TIMEOUT_S = 60.0

# Client ids that hold the EGL plugin now. The plugin makes its EGL context current once, when
# it is loaded (``pybullet 3.2.7 sdist: examples/OpenGLWindow/EGLOpenGLWindow.cpp:272``), and
# never again, so a second EGL client in one process would draw with the first one's context.
_EGL_CLIENTS: set[int] = set()

# pybullet functions that take no ``physicsClientId`` (pure maths), as listed by
# ``pybullet_utils.bullet_client.BulletClient``; everything else gets this client's id bound.
_CLIENTLESS = frozenset(
    {
        "invertTransform",
        "multiplyTransforms",
        "getMatrixFromQuaternion",
        "getEulerFromQuaternion",
        "computeViewMatrixFromYawPitchRoll",
        "computeProjectionMatrixFOV",
        "getQuaternionFromEuler",
    }
)


@dataclass(frozen=True)
class PhysicsSettings:
    """RMB's TACTO physics (``RMB: envs/tacto/TactoSawyerEnvBase.py:119-126``).

    Attributes:
        timestep: One ``stepSimulation`` in seconds (RMB 0.005).
        substeps: Physics steps per control step (RMB 6, so one action lasts 0.03 s).
        num_solver_iterations: Constraint solver iterations (RMB 200, PyBullet's default 50);
            RMB raised it so that grasped objects do not slip out of the WSG50 fingers.
        solver_residual_threshold: Solver stop criterion (RMB 1e-8, PyBullet's default 1e-7).
        enable_cone_friction: 1 uses the friction cone instead of PyBullet's pyramid
            approximation (RMB 1, which is also PyBullet's default).
        gravity: Acceleration along world z in m/s^2 (RMB -9.8).
        deterministic_overlapping_pairs: 1 sorts Bullet's contact pair cache, whose order
            otherwise depends on the pairs' history, so an episode does not depend on the ones
            before it (not set by RMB; without it the same seed gave Insert joints 1e-4 rad
            apart after teleporting the clamped board).
    """

    timestep: float = 0.005
    substeps: int = 6
    num_solver_iterations: int = 200
    solver_residual_threshold: float = 1e-8
    enable_cone_friction: int = 1
    gravity: float = -9.8
    deterministic_overlapping_pairs: int = 1

    def __post_init__(self) -> None:
        if not self.timestep > 0:
            raise ValueError(f"timestep must be positive, got {self.timestep!r}")
        if isinstance(self.substeps, bool) or not isinstance(self.substeps, int):
            raise ValueError(f"substeps must be an int, got {self.substeps!r}")
        if self.substeps < 1:
            raise ValueError(f"substeps must be >= 1, got {self.substeps}")
        if self.num_solver_iterations < 1:
            raise ValueError(
                f"num_solver_iterations must be >= 1, got {self.num_solver_iterations}"
            )
        if self.enable_cone_friction not in (0, 1):
            raise ValueError(
                f"enable_cone_friction must be 0 or 1, got {self.enable_cone_friction}"
            )

    @property
    def control_dt(self) -> float:
        """Seconds one control step (one action) lasts: ``timestep * substeps`` (RMB 0.03)."""
        return self.timestep * self.substeps


# --------------------------------------------------------------------------- EGL availability


def egl_plugin_path() -> str | None:
    """Path of PyBullet's ``eglRenderer`` extension, or ``None`` when this build has none.

    The pybullet sdist builds it on Linux only; ``importlib.util.find_spec`` finds it without
    importing it (``pkgutil.get_loader`` is deprecated on Python 3.12).
    """
    spec = importlib.util.find_spec(_EGL_MODULE)
    return spec.origin if spec is not None else None


# The names glad's EGL loader inside the plugin tries, in order
# (``pybullet 3.2.7 sdist: examples/ThirdPartyLibs/glad/egl.c:419``).
_LIBEGL_NAMES = ("libEGL.so.1", "libEGL.so")


def _libegl_failure() -> str | None:
    """Why libEGL cannot be loaded, or ``None`` when it can (dlopen is harmless in-process).

    Without it the plugin prints "failed to EGL with glad." and exits the process. Seen on a
    GPU machine whose image had NVIDIA's ``libEGL_nvidia`` but no libglvnd ``libEGL.so.1``.
    """
    errors = []
    for name in _LIBEGL_NAMES:
        try:
            ctypes.CDLL(name)
        except OSError as exc:
            errors.append(str(exc))
        else:
            return None
    return (
        "libEGL.so.1 cannot be loaded (install libglvnd's libEGL, Debian/Ubuntu package "
        f"libegl1, plus a vendor: libegl-mesa0 or NVIDIA's driver): {errors[0]}"
    )


_PROBE_SOURCE = """
import sys
import pybullet as p
cid = p.connect(p.DIRECT)
plugin = p.loadPlugin(sys.argv[1], "_eglRendererPlugin", physicsClientId=cid)
if plugin < 0:
    sys.exit(3)
p.getCameraImage(8, 8, renderer=p.ER_BULLET_HARDWARE_OPENGL, physicsClientId=cid)
p.unloadPlugin(plugin, physicsClientId=cid)
p.disconnect(cid)
print("EGL_PROBE_OK")
"""


@functools.cache
def _egl_probe_failure(path: str) -> str | None:
    """Why the EGL plugin fails here, found in a child process, or ``None`` when it works.

    The plugin calls ``exit(EXIT_FAILURE)`` on every EGL error (no libEGL, no device, a bad
    ``EGL_VISIBLE_DEVICES`` index, no context: ``EGLOpenGLWindow.cpp:115-283``), which would end
    this process with no exception to catch, so it is first loaded and used once in a child
    with this process's environment. The answer is cached per process (1.2 s once,
    measured on the 2-core dev machine).
    """
    try:
        done = subprocess.run(
            [sys.executable, "-c", _PROBE_SOURCE, path],
            capture_output=True,
            text=True,
            timeout=_PROBE_TIMEOUT_S,
            check=False,
        )
    except (OSError, subprocess.TimeoutExpired) as exc:
        return f"the EGL probe process did not finish ({exc})"
    if done.returncode == 0 and "EGL_PROBE_OK" in done.stdout:
        gl = [line for line in done.stdout.splitlines() if line.startswith("GL_RENDERER")]
        logger.info("PyBullet's EGL plugin works here: %s", gl[0] if gl else "ok")
        return None
    lines = [
        line
        for line in (done.stderr + done.stdout).splitlines()
        if line.strip() and not line.startswith("pybullet build time")
    ]
    tail = "; ".join(lines[-2:]) if lines else "no output"
    return f"loading it in a probe process failed with exit code {done.returncode} ({tail})"


def egl_unavailable_reason() -> str | None:
    """Why :func:`connect` cannot use EGL now, or ``None`` when it can.

    Returns:
        A sentence naming the cause: no ``eglRenderer`` extension in this pybullet build,
        another client of this process already holding the plugin, no loadable libEGL, or
        the probe's failure (its exit code and last output lines).
    """
    path = egl_plugin_path()
    if path is None:
        return (
            f"this pybullet build has no {_EGL_MODULE!r} extension "
            "(pybullet's sdist builds it on Linux only)"
        )
    if _EGL_CLIENTS:
        return (
            f"client {min(_EGL_CLIENTS)} of this process already uses the EGL plugin, which "
            "makes its GL context current only once; close it first"
        )
    return _libegl_failure() or _egl_probe_failure(path)


# --------------------------------------------------------------------------- the client


def _release(client_id: int, plugin_id: int | None) -> None:
    """Unload the plugin and disconnect (also run by the finalizer of a forgotten client)."""
    _EGL_CLIENTS.discard(client_id)
    if not p.isConnected(physicsClientId=client_id):
        return
    if plugin_id is not None:
        p.unloadPlugin(plugin_id, physicsClientId=client_id)
    p.disconnect(physicsClientId=client_id)


class PybulletClient:
    """One headless PyBullet physics client with RMB's settings; make it with :func:`connect`.

    Any pybullet function is also reachable as an attribute with this client's id bound, as
    with ``pybullet_utils.bullet_client.BulletClient``: ``client.loadURDF("plane.urdf")``.

    Attributes:
        client_id: PyBullet's ``physicsClientId`` of this client.
        settings: The physics settings applied on connect and on every :meth:`reset`.
        renderer: ``"egl"`` when the EGL plugin is loaded (camera images use
            ``ER_BULLET_HARDWARE_OPENGL``), else ``"tiny"`` (``ER_TINY_RENDERER``).
        thread_id: ``threading.get_ident()`` of the thread that connected it; the only one
            that may render when ``renderer == "egl"``.
    """

    def __init__(self, client_id: int, settings: PhysicsSettings, plugin_id: int | None) -> None:
        self.client_id = client_id
        self.settings = settings
        self._plugin_id = plugin_id
        self.renderer: Literal["egl", "tiny"] = "egl" if plugin_id is not None else "tiny"
        self.thread_id = threading.get_ident()
        self._finalizer = weakref.finalize(self, _release, client_id, plugin_id)
        self.apply_settings()

    @property
    def closed(self) -> bool:
        """Whether :meth:`close` ran (or PyBullet lost the connection)."""
        return not self._finalizer.alive or not p.isConnected(physicsClientId=self.client_id)

    def apply_settings(self) -> None:
        """Apply :attr:`settings` (and the ``pybullet_data`` search path) to the server."""
        s = self.settings
        cid = self.client_id
        p.setAdditionalSearchPath(pybullet_data.getDataPath(), physicsClientId=cid)
        p.setPhysicsEngineParameter(
            fixedTimeStep=s.timestep,
            numSolverIterations=s.num_solver_iterations,
            solverResidualThreshold=s.solver_residual_threshold,
            enableConeFriction=s.enable_cone_friction,
            deterministicOverlappingPairs=s.deterministic_overlapping_pairs,
            physicsClientId=cid,
        )
        p.setGravity(0.0, 0.0, s.gravity, physicsClientId=cid)

    def step_control(self) -> None:
        """Advance one control step: ``settings.substeps`` physics steps (RMB 6 x 0.005 s).

        Motor targets set before the call hold for all substeps; RMB re-sends the same
        targets every substep, which PyBullet's motors make equivalent.
        """
        self._check_open()
        for _ in range(self.settings.substeps):
            p.stepSimulation(physicsClientId=self.client_id)

    def reset(self) -> None:
        """Empty the world and re-apply the settings (``resetSimulation`` restores defaults).

        The EGL plugin stays loaded through ``resetSimulation`` (images still differ from
        TinyRenderer's after it, checked in the tests), so it is reloaded only if PyBullet
        dropped it.
        """
        self._check_open()
        p.resetSimulation(physicsClientId=self.client_id)
        self.apply_settings()

    def close(self) -> None:
        """Unload the EGL plugin and disconnect; calling it again does nothing."""
        self._finalizer()

    def check_render_thread(self) -> None:
        """Raise unless camera images may be taken from the calling thread.

        The EGL context is current only on the thread that loaded the plugin; rendering
        from another one segfaults (measured), so this turns that into an exception. Loading,
        stepping and moving bodies from another thread worked; TinyRenderer has no limit.

        Raises:
            RuntimeError: ``renderer == "egl"`` and this is not the connecting thread.
        """
        if self.renderer == "egl" and threading.get_ident() != self.thread_id:
            raise RuntimeError(
                f"PyBullet client {self.client_id} renders with EGL, whose GL context is "
                "current only on the thread that connected it; render from that thread, or "
                'connect with renderer="tiny"'
            )

    def _check_open(self) -> None:
        if self.closed:
            raise RuntimeError(f"PyBullet client {self.client_id} is closed")

    def __getattr__(self, name: str) -> Any:
        attribute = getattr(p, name)
        if name == "getCameraImage":
            self.check_render_thread()
        if inspect.isbuiltin(attribute) and name not in _CLIENTLESS:
            return functools.partial(attribute, physicsClientId=self.client_id)
        return attribute

    def __enter__(self) -> PybulletClient:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    def __repr__(self) -> str:
        state = "closed" if self.closed else "open"
        return f"PybulletClient(client_id={self.client_id}, renderer={self.renderer!r}, {state})"


def _load_egl(client_id: int) -> int:
    """Load the EGL plugin into ``client_id``; returns its plugin id (raises if refused)."""
    path = egl_plugin_path()
    assert path is not None  # egl_unavailable_reason() said it exists
    plugin_id = p.loadPlugin(path, _EGL_PLUGIN_SUFFIX, physicsClientId=client_id)
    if plugin_id < 0:
        raise RuntimeError(f"pybullet refused to load the EGL plugin {path}")
    _EGL_CLIENTS.add(client_id)
    return plugin_id


def _choose_egl(renderer: str) -> bool:
    """Whether to load the EGL plugin for ``renderer``; warns once when "auto" falls back."""
    if renderer == "tiny":
        return False
    reason = egl_unavailable_reason()
    if reason is None:
        return True
    if renderer == "egl":
        raise RuntimeError(f"PyBullet's EGL renderer is not available: {reason}")
    warnings.warn(
        f"PyBullet renders with TinyRenderer (software, CPU) instead of EGL: {reason}",
        RuntimeWarning,
        stacklevel=3,
    )
    return False


def connect(settings: PhysicsSettings | None = None, renderer: Renderer = "auto") -> PybulletClient:
    """Open a headless (``p.DIRECT``) client with RMB's physics and an offscreen renderer.

    Nothing about EGL is set up at package import: the plugin is probed and loaded here, and
    only for the client that asks. PyBullet's plugin honours ``EGL_VISIBLE_DEVICES`` (an index
    into ``eglQueryDevicesEXT``'s list); nothing else in the environment is read or changed.

    Connect costs, measured (2-core dev machine, Mesa llvmpipe, load average ~5 from other
    work): the EGL probe 1.2 s once per process, then 0.6 s per EGL client (llvmpipe start;
    0.1 s on an H200 with NVIDIA's EGL), 30-40 ms per TinyRenderer client. Frame times are in
    :func:`rmb_lerobot.envs.pybullet.camera.render`.

    Args:
        settings: Physics settings; ``None`` means RMB's (:class:`PhysicsSettings`).
        renderer: ``"egl"`` loads PyBullet's EGL renderer plugin (hardware OpenGL, or Mesa's
            llvmpipe without a GPU) and raises if it cannot; ``"tiny"`` uses TinyRenderer;
            ``"auto"`` tries EGL and falls back to TinyRenderer with one ``RuntimeWarning``
            naming why. Only one client per process can hold the EGL plugin at a time.

    Returns:
        The open client; close it with :meth:`PybulletClient.close` or a ``with`` block.

    Raises:
        ValueError: ``renderer`` is not one of :data:`RENDERERS`.
        RuntimeError: PyBullet refused the connection, or ``"egl"`` cannot be used.
    """
    if renderer not in RENDERERS:
        raise ValueError(f"renderer must be one of {RENDERERS}, got {renderer!r}")
    settings = PhysicsSettings() if settings is None else settings
    use_egl = _choose_egl(renderer)
    client_id = p.connect(p.DIRECT)
    if client_id < 0:
        raise RuntimeError("pybullet could not open a DIRECT physics client")
    try:
        plugin_id = _load_egl(client_id) if use_egl else None
    except BaseException:
        p.disconnect(physicsClientId=client_id)
        raise
    client = PybulletClient(client_id, settings, plugin_id)
    logger.debug("Connected %r", client)
    return client
