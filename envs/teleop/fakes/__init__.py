"""Test doubles of the teleoperation devices, at the SDK boundary the real code talks across.

:mod:`.spacemouse`: a fake ``pyspacemouse`` module (the 2.x calls our device makes) fed a
scripted state stream. :mod:`.dynamixel`: a chain of Dynamixel servos speaking protocol 2.0 on
a pseudo-terminal, which the unmodified ``dynamixel-sdk`` opens as a serial port. Neither
needs hardware, a display or the network.
"""
