"""Stand-ins for PARAM groups of firmware modules the emulation does not run, which stock clients use.

On both plants: ``led`` (led.c: ``bitmask``, which cflib's swarm examples set to light a drone up; the
emulation has no LEDs, so the value is kept and read back, and ``leds_lit`` says which would be on) and
``cpu`` (system.c: the STM32F405's flash size in kB and its 96-bit unique id, read-only). The firmware plant
serves the firmware's own groups besides (``sil/tables.py``); the reduced plant serves only these, the
``deck`` flags, ``stateEstimate``, ``supervisor`` and the app's groups (docs/crtp.md lists what it lacks).
"""
from crazyflie_app.firmware.logparam import PARAM_UINT8, PARAM_UINT16, PARAM_UINT32, param_add, param_group

STM32F405_FLASH_KB = 1024
EMULATED_CPU_ID = (0x00454D55, 0x4C415445, 0x44434631)  # "EMU", "LATE", "DCF1": no real MCU has this id

LED_PARAM = param_group("led", [
    param_add(PARAM_UINT8, "bitmask", "led_bitmask", "", "LEDs forced on by a client (led.c; 0: the firmware's "
              "own sequences)"),
])
CPU_PARAM = param_group("cpu", [
    param_add(PARAM_UINT16, "flash", "cpu_flash", "kB", "MCU flash size", read_only=True),
    param_add(PARAM_UINT32, "id0", "cpu_id0", "", "MCU unique id, word 0", read_only=True),
    param_add(PARAM_UINT32, "id1", "cpu_id1", "", "MCU unique id, word 1", read_only=True),
    param_add(PARAM_UINT32, "id2", "cpu_id2", "", "MCU unique id, word 2", read_only=True),
])
STANDIN_PARAM_GROUPS = (LED_PARAM, CPU_PARAM)


class StandIns:
    """The variables behind the stand-in groups."""

    def __init__(self):
        self.led_bitmask = 0
        self.cpu_flash = STM32F405_FLASH_KB
        self.cpu_id0, self.cpu_id1, self.cpu_id2 = EMULATED_CPU_ID

    @property
    def leds_lit(self) -> int:
        """The LEDs a client forced on (bit i: LED i), as led.c's ledBitmaskParamCallback sets them."""
        return self.led_bitmask
