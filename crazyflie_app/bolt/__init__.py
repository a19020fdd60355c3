"""The Bolt navigation app in C (``src/``, built into ``bolt.bin`` by the firmware's out-of-tree app build) and
its host bindings: ``c_core`` (ctypes binding of the pure C core) and ``c_app`` (the C app on the emulated
firmware, beside the Python app of ``crazyflie_app.app``)."""
