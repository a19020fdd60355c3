"""The firmware plant's tests need its library (make firmware-sil, which make setup runs when the firmware
source is at hand); without it they skip, saying how to build it."""
import os

import pytest

from crazyflie_app.firmware.sil.stack import library_path

needs_firmware_plant = pytest.mark.skipif(
    not os.path.exists(library_path()),
    reason="the firmware plant is not built: make firmware-sil (needs the Crazyflie firmware source)")
