"""Choice of MuJoCo's OpenGL backend, tested without needing EGL or OSMesa to be present."""

import subprocess
import sys

from rmb_lerobot.envs.mujoco.gl import choose_backend, gl_context_class


def loads_only(*names):
    return lambda library: library in names


def test_user_choice_is_kept():
    env = {"MUJOCO_GL": "glfw"}
    assert choose_backend(env, loads_only("EGL", "OSMesa")) == "glfw"
    assert gl_context_class(env, loads_only("EGL"))[0] == "glfw"
    assert env == {"MUJOCO_GL": "glfw"}


def test_egl_is_preferred():
    assert choose_backend({}, loads_only("EGL", "OSMesa")) == "egl"


def test_falls_back_to_osmesa_without_egl():
    assert choose_backend({}, loads_only("OSMesa")) == "osmesa"


def test_leaves_default_when_nothing_loads():
    assert choose_backend({}, loads_only()) is None


def test_empty_value_counts_as_unset():
    assert choose_backend({"MUJOCO_GL": ""}, loads_only("OSMesa")) == "osmesa"


def test_a_renderer_is_headless_whatever_was_imported_first():
    """With no MUJOCO_GL and ``mujoco`` imported before the package, a renderer still gets
    EGL's context on this (display-less) machine, and nothing sets MUJOCO_GL for the process."""
    code = (
        "import os\n"
        "for var in ('MUJOCO_GL', 'PYOPENGL_PLATFORM', 'DISPLAY'): os.environ.pop(var, None)\n"
        "import mujoco\n"
        "from rmb_lerobot.envs.mujoco.gl import gl_context_class\n"
        "from rmb_lerobot.envs.registry import ENVS\n"
        "env = ENVS['insert'].make(cameras=('front',), image_size=(32, 24))\n"
        "obs, _ = env.reset(seed=0)\n"
        "assert obs['pixels']['front'].std() > 0, 'blank image'\n"
        "backend, cls = gl_context_class()\n"
        "assert backend == 'egl' and cls.__module__ == 'mujoco.egl', (backend, cls)\n"
        "assert 'MUJOCO_GL' not in os.environ\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True, timeout=300)
