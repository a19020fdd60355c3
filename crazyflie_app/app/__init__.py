"""The Bolt navigation app, ported to Python: the pure core (``navigation_core`` and one module per job) and the
thin firmware layer around it (``navigation``, ``app_main``). See ``navigation.py`` for the C -> Python name
table; ``crazyflie_app/bolt`` holds the same app in C."""
