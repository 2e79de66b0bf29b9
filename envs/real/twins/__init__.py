"""Simulated twins of the real arms' controllers, for tests and dry runs without hardware.

Each twin answers its SDK's calls with the SDK's signatures and return conventions, backed by
the arm's MuJoCo model stepped in wall-clock time (:mod:`.sim`): :mod:`.ur5e` (ur-rtde's
``RTDEControlInterface`` / ``RTDEReceiveInterface`` and a Robotiq URCap server on loopback,
:mod:`.robotiq_server`) and :mod:`.xarm7` (``XArmAPI``). Each has fault hooks (dropped
connection, SDK error codes, protective stop, gripper fault, stale state) and stops the arm
by itself on a joint limit or a collision. Twins only ever listen on loopback.
"""
