"""Real arms: drivers (an SDK or its simulated twin) behind one small interface, one safety
layer every command passes, and the devices built on them.

Importing this package imports no hardware SDK: each driver imports its SDK when it connects,
and a missing extra gives an error naming it.
"""
