"""The MuJoCo backend and everything MuJoCo-specific (models, scenes, rendering).

Importing it sets nothing up: the OpenGL backend is chosen when a renderer is made
(:func:`rmb_lerobot.envs.mujoco.gl.gl_context_class`), so a PyBullet or real-arm env never
touches MuJoCo's settings and ``import mujoco`` may come first.
"""
