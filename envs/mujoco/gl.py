"""Pick MuJoCo's OpenGL backend for a renderer, headless where the machine allows.

MuJoCo reads ``MUJOCO_GL`` once, when ``mujoco`` is first imported, to pick its
``mujoco.GLContext``. Rather than setting that variable for the whole process at package import
(which must then precede every ``import mujoco``, and changes what other libraries see), the
renderer asks :func:`gl_context_class` when it is made: a value the user set is always kept;
otherwise EGL's or OSMesa's context class is taken directly from its MuJoCo module.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import importlib
import os
from collections.abc import Callable, Mapping

# MUJOCO_GL value -> the shared library that backend loads.
_BACKEND_LIBRARIES = {"egl": "EGL", "osmesa": "OSMesa"}


def library_loads(name: str) -> bool:
    """Whether the shared library ``lib<name>`` can be found and loaded."""
    path = ctypes.util.find_library(name)
    if path is None:
        return False
    try:
        ctypes.CDLL(path)
    except OSError:
        return False
    return True


def choose_backend(
    environ: Mapping[str, str], loads: Callable[[str], bool] = library_loads
) -> str | None:
    """The ``MUJOCO_GL`` value to use: the user's, else the first backend whose library loads
    (EGL, then OSMesa), else ``None`` (leave MuJoCo's default)."""
    user = environ.get("MUJOCO_GL")
    if user:
        return user
    for backend, library in _BACKEND_LIBRARIES.items():
        if loads(library):
            return backend
    return None


def gl_context_class(
    environ: Mapping[str, str] | None = None, loads: Callable[[str], bool] = library_loads
) -> tuple[str | None, type]:
    """The OpenGL backend for a new renderer and MuJoCo's context class for it.

    Called where a renderer is made, not at import: choosing needs no environment variable set
    for the whole process, and works whenever ``mujoco`` was imported. A ``MUJOCO_GL`` the user
    set is MuJoCo's own choice (``mujoco.GLContext``, fixed when ``mujoco`` was imported);
    otherwise EGL when its library loads (headless, works with Mesa's software renderer), else
    OSMesa, each through its own MuJoCo module (which sets PyOpenGL's platform to match), else
    MuJoCo's default (GLFW, which needs a display).

    Args:
        environ: The environment to read (default ``os.environ``); it is not changed here.
        loads: Whether a shared library loads (for tests).

    Returns:
        ``(backend, GLContext class)``; ``backend`` is None for MuJoCo's default.
    """
    environ = os.environ if environ is None else environ
    backend = choose_backend(environ, loads)
    if environ.get("MUJOCO_GL") or backend not in _BACKEND_LIBRARIES:
        import mujoco

        return backend, mujoco.GLContext
    module = importlib.import_module(f"mujoco.{backend}")
    return backend, module.GLContext
