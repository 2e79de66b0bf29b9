"""Teleoperation: input devices, the phase loop of RMB's ``Teleop.py`` and ``rmb-teleop``."""
