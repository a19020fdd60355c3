"""The Crazyflie half of ForaNav: the Bolt navigation app (``navigation``) and the firmware it runs on
(``firmware``), emulated on a PC. See ``navigation.py`` for the C -> Python name table."""
