"""MuJoCo models of RMB's other robots, composed with :class:`mujoco.MjSpec` from PyPI packages.

Each module builds one robot (arm + gripper + wrist F/T sensor + hand camera) and returns a
:class:`~rmb_lerobot.envs.mujoco.models.common.RobotModel`: the spec and the names a robot
record needs. Model files are read where their package installed them; nothing is copied.
"""
