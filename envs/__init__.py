"""RoboManipBaselines environments (gymnasium), installed as ``rmb_lerobot.envs``.

Importing this package imports no simulator and changes no environment variable: each
simulator's backend package sets up its own rendering when it is imported
(:mod:`rmb_lerobot.envs.mujoco` chooses MuJoCo's OpenGL backend before ``mujoco`` loads).
"""
