"""Choice of MuJoCo's OpenGL backend, tested without needing EGL or OSMesa to be present."""

import json
import os
import subprocess
import sys

from rmb_lerobot.envs.mujoco.gl import choose_backend, gl_context_class, library_loads


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


# Run with the variables a user (or the Makefile, which exports MUJOCO_GL=egl for the test
# suite) may have set removed from the child's environment: the choice made is the package's.
CHILD = """
import json, os
import mujoco  # before the package: MuJoCo's own default is then fixed (GLFW, needs a display)
from rmb_lerobot.envs.registry import ENVS
env = ENVS["insert"].make(cameras=("front",), image_size=(32, 24))
obs, _ = env.reset(seed=0)
from rmb_lerobot.envs.mujoco.gl import gl_context_class
print(json.dumps({
    "backend": gl_context_class()[0],
    "renderer_context": type(env.sim._get_renderer()._gl).__module__,
    "std": float(obs["pixels"]["front"].std()),
    "environ": {v: os.environ.get(v) for v in ("MUJOCO_GL", "PYOPENGL_PLATFORM")},
}))
"""


def test_a_renderer_is_headless_whatever_was_imported_first():
    """With no MUJOCO_GL, PYOPENGL_PLATFORM or display, and ``mujoco`` imported before the
    package, a renderer gets the headless backend gl.py documents: EGL where its library loads
    (this machine and CI), else OSMesa; and nothing sets MUJOCO_GL for the process."""
    unset = ("MUJOCO_GL", "PYOPENGL_PLATFORM", "DISPLAY", "WAYLAND_DISPLAY")
    env = {k: v for k, v in os.environ.items() if k not in unset}
    expected = next(
        (b for b, lib in (("egl", "EGL"), ("osmesa", "OSMesa")) if library_loads(lib)), None
    )
    assert expected is not None, "neither libEGL nor libOSMesa loads: no headless rendering here"
    result = subprocess.run(
        [sys.executable, "-c", CHILD], env=env, capture_output=True, text=True, timeout=300
    )
    assert result.returncode == 0, result.stderr[-3000:]
    child = json.loads(result.stdout.strip().splitlines()[-1])
    assert child["backend"] == expected
    assert child["renderer_context"] == f"mujoco.{expected}"  # the context the renderer made
    assert child["std"] > 0, "blank image"
    # MuJoCo's EGL/OSMesa module points PyOpenGL at the same platform; MUJOCO_GL stays unset.
    assert child["environ"] == {"MUJOCO_GL": None, "PYOPENGL_PLATFORM": expected}
