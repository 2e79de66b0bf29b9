"""RoboManipBaselines environments (gymnasium), installed as ``rmb_lerobot.envs``.

The OpenGL backend for headless rendering is chosen here, before anything imports ``mujoco``.
"""

from rmb_lerobot.envs.mujoco.gl import configure_gl_backend

configure_gl_backend()
