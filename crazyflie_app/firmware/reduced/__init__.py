"""The reduced plant (``--plant reduced``, the default): the Python commander and supervisor of the emulation
over a first-order closed-loop MAV model (``mav_model``), stepped at the position loop's rate
(``stack.ReducedFlightStack``). The other plant, the real firmware over a rigid body, is ``firmware/sil``."""
