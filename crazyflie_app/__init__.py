"""The Crazyflie half of ForaNav, three rooms: ``app`` (the Bolt navigation app ported to Python), ``bolt``
(the same app in C, built into ``bolt.bin``, and its host bindings) and ``firmware`` (the emulated Crazyflie
both apps run on, with its two plants: ``firmware/reduced`` and the real firmware's ``firmware/sil``)."""
