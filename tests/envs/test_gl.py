"""Choice of MuJoCo's OpenGL backend, tested without needing EGL or OSMesa to be present."""

from rmb_lerobot.envs.mujoco.gl import choose_backend, configure_gl_backend


def loads_only(*names):
    return lambda library: library in names


def test_user_choice_is_kept():
    env = {"MUJOCO_GL": "glfw"}
    assert choose_backend(env, loads_only("EGL", "OSMesa")) == "glfw"
    assert configure_gl_backend(env, loads_only("EGL")) == "glfw"
    assert env == {"MUJOCO_GL": "glfw"}


def test_egl_is_preferred():
    env = {}
    assert configure_gl_backend(env, loads_only("EGL", "OSMesa")) == "egl"
    assert env == {"MUJOCO_GL": "egl", "PYOPENGL_PLATFORM": "egl"}


def test_falls_back_to_osmesa_without_egl():
    env = {}
    assert configure_gl_backend(env, loads_only("OSMesa")) == "osmesa"
    assert env["MUJOCO_GL"] == "osmesa" and env["PYOPENGL_PLATFORM"] == "osmesa"


def test_leaves_default_when_nothing_loads():
    env = {}
    assert configure_gl_backend(env, loads_only()) is None
    assert env == {}


def test_empty_value_counts_as_unset_and_pyopengl_choice_is_kept():
    env = {"MUJOCO_GL": "", "PYOPENGL_PLATFORM": "egl"}
    assert configure_gl_backend(env, loads_only("OSMesa")) == "osmesa"
    assert env["PYOPENGL_PLATFORM"] == "egl"


def test_package_import_selected_a_headless_backend():
    import os

    import rmb_lerobot.envs  # noqa: F401

    assert os.environ.get("MUJOCO_GL") in ("egl", "osmesa", "glfw", "glx")
