"""Arm drivers: each vendor's SDK (or the arm's MuJoCo twin) behind
:class:`~rmb_lerobot.envs.real.driver.ArmDriver`.

- :mod:`.ur5e`: UR5e with ur-rtde and a Robotiq 2F-85 on the URCap socket (:mod:`.robotiq`);
  extra ``ur5e``.
- :mod:`.xarm7`: xArm7 with xarm-python-sdk; extra ``xarm7``.

A config's ``driver`` chooses ``"sdk"`` (the arm at ``host``) or ``"sim"`` (the twin in
:mod:`rmb_lerobot.envs.real.twins`, on loopback). Importing these modules imports no SDK:
:meth:`connect` does, and a missing extra raises an ``ImportError`` naming
``pip install 'rmb_lerobot[<extra>]'``. Drivers do no clamping: every command they get has
passed :mod:`rmb_lerobot.envs.real.safety`.
"""
