"""Pick MuJoCo's OpenGL backend before ``mujoco`` is imported.

MuJoCo reads ``MUJOCO_GL`` once, when the ``mujoco`` package is first imported, so this module
must run before that (``rmb_lerobot.envs`` imports it first thing). A value the user set is
always kept. Otherwise EGL is chosen when its library loads (headless, works with Mesa's
software renderer), else OSMesa, else MuJoCo's default (GLFW, which needs a display).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import logging
import os
import sys
from collections.abc import Callable, MutableMapping

logger = logging.getLogger(__name__)

# MUJOCO_GL value -> the shared library that backend loads.
_BACKEND_LIBRARIES = {"egl": "EGL", "osmesa": "OSMesa"}
# PyOpenGL must agree with MuJoCo on the platform.
_PYOPENGL_PLATFORM = {"egl": "egl", "osmesa": "osmesa"}


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
    environ: MutableMapping[str, str], loads: Callable[[str], bool] = library_loads
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


def configure_gl_backend(
    environ: MutableMapping[str, str] | None = None,
    loads: Callable[[str], bool] = library_loads,
) -> str | None:
    """Set ``MUJOCO_GL`` (and ``PYOPENGL_PLATFORM``) in ``environ`` unless the user set it.

    Returns the backend in effect. Warns when ``mujoco`` was already imported without a backend
    choice: MuJoCo has then fixed its default and offscreen rendering may need a display.
    """
    environ = os.environ if environ is None else environ
    if environ.get("MUJOCO_GL"):
        return environ["MUJOCO_GL"]
    if "mujoco" in sys.modules and environ is os.environ:
        logger.warning(
            "mujoco was imported before rmb_lerobot.envs; set MUJOCO_GL=egl (or osmesa) in the "
            "environment for headless rendering"
        )
        return None
    backend = choose_backend(environ, loads)
    if backend is None:
        return None
    environ["MUJOCO_GL"] = backend
    if backend in _PYOPENGL_PLATFORM:
        environ.setdefault("PYOPENGL_PLATFORM", _PYOPENGL_PLATFORM[backend])
    return backend
