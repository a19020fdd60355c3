"""The emulated Crazyflie: scheduler, commander, supervisor, stabilizer task, estimate, log/param, console.

``Crazyflie(seed=..., model_config=..., decks=..., plant=...)`` boots the services an app needs;
``x_task_create`` adds app tasks; ``run_until(tick)`` advances the whole system. Commander, supervisor, plant
and stabilizer task come from one of two flight stacks:

* ``plant="reduced"`` (default, ``ReducedFlightStack``): the Python commander and supervisor and the reduced
  MAV model; its stabilizer task runs at the 100 Hz position-loop rate and wakes on the exact tick of any
  watchdog threshold, so level-out and lock happen when the firmware would, without stepping Python at 1 kHz;
* ``plant="firmware"`` (``sil.plant.FirmwareFlightStack``): the real firmware's commander, supervisor, PID
  controller and Kalman estimator in C over a rigid-body quadrotor, its stabilizer task every tick.
"""
from collections.abc import Sequence
from typing import Any

from crazyflie_app.firmware import freertos
from crazyflie_app.firmware.logparam import (LOG_FLOAT, LOG_UINT8, PARAM_UINT8, LogParamRegistry, log_add,
                                              log_group, param_add, param_group)
from crazyflie_app.firmware.reduced.mav_model import MavModelConfig
from crazyflie_app.firmware.reduced.stack import ReducedFlightStack
from crazyflie_app.firmware.sil.plant import FirmwareFlightStack
from crazyflie_app.firmware.sil.stack import FirmwarePlantConfig
from crazyflie_app.firmware.standins import STANDIN_PARAM_GROUPS, StandIns
from crazyflie_app.firmware.supervisor import SUPERVISOR_STATES
from crazyflie_app.firmware.uart2 import Uart2

STABILIZER_TASK_PRI = 5
UART2_RX_TASK_PRI = 5  # stands in for the USART2 receive interrupt
PLANTS = ("reduced", "firmware")  # the reduced model (default) or the real firmware over a rigid body
# platform_bolt.c / platform_cf2.c: the name the platform service gives a client (require_arming: the Bolt)
DEVICE_TYPE_NAMES = {True: "Crazyflie Bolt 1.1", False: "Crazyflie 2.1"}

STATE_ESTIMATE_LOG = log_group("stateEstimate", [
    log_add(LOG_FLOAT, "x", "x", "m", "estimated position, global frame"),
    log_add(LOG_FLOAT, "y", "y", "m", "estimated position, global frame"),
    log_add(LOG_FLOAT, "z", "z", "m", "estimated height"),
    log_add(LOG_FLOAT, "vx", "vx", "m/s", "estimated velocity, global frame"),
    log_add(LOG_FLOAT, "vy", "vy", "m/s", "estimated velocity, global frame"),
    log_add(LOG_FLOAT, "vz", "vz", "m/s", "estimated vertical velocity"),
    log_add(LOG_FLOAT, "yaw", "yaw", "deg", "estimated yaw, counter-clockwise"),
    log_add(LOG_FLOAT, "roll", "roll", "deg", "estimated roll"),
    log_add(LOG_FLOAT, "pitch", "pitch", "deg", "estimated pitch (the firmware's legacy sign: nose up)"),
])
SUPERVISOR_LOG = log_group("supervisor", [
    log_add(LOG_UINT8, "info", "state_index", "", "supervisor state: " + ", ".join(
        "%d %s" % (i, s) for i, s in enumerate(SUPERVISOR_STATES)) + " (firmware plant: supervisorState_t)"),
])
# deck.bc*: the decks the app checks, then the presence flags of the other deck drivers a firmware build carries
# (and cfclient reads on connect); a deck not in ``decks`` reads 0
DECK_NAMES = {"bcFlow2": "Flow deck v2", "bcLoco": "Loco Positioning deck", "bcFlow": "Flow deck v1",
              "bcZRanger": "Z-ranger deck", "bcZRanger2": "Z-ranger deck v2", "bcDWM1000": "Loco deck (its radio)",
              "bcLighthouse4": "Lighthouse deck", "bcMultiranger": "Multi-ranger deck", "bcLedRing": "LED-ring deck"}
DECK_PARAM = param_group("deck", [param_add(PARAM_UINT8, name, name, "", "nonzero if the %s is attached" % deck, True)
                                  for name, deck in DECK_NAMES.items()])


class _Decks:
    def __init__(self, decks):
        for name in DECK_NAMES:
            setattr(self, name, 1 if name in decks else 0)


class _SupervisorInfo:
    def __init__(self, supervisor):
        self._supervisor = supervisor

    @property
    def state_index(self):
        return self._supervisor.state_index


class Console:
    """DEBUG_PRINT and eventTrigger: kept lines plus listeners (telemetry taps)."""

    def __init__(self, clock: freertos.Scheduler, max_lines: int = 1000):
        self._clock = clock
        self.lines = []  # (tick, module, text), the newest max_lines
        self._max_lines = max_lines
        self.listeners = []  # callables(tick, module, text)
        self.event_listeners = []  # callables(tick, name, payload dict)

    def debug_print(self, module: str, text: str) -> None:
        tick = self._clock.x_task_get_tick_count()
        self.lines.append((tick, module, text))
        if len(self.lines) > self._max_lines:
            del self.lines[0]
        for listener in self.listeners:
            listener(tick, module, text)

    def event_trigger(self, name: str, **payload: Any) -> None:
        tick = self._clock.x_task_get_tick_count()
        for listener in self.event_listeners:
            listener(tick, name, payload)


class _Forward:
    """A firmware call of the Crazyflie that one of its services implements, under the same name:
    ``cf.log_get_float(var_id)`` is ``cf.registry.log_get_float(var_id)``."""

    def __init__(self, service: str):
        self.service = service
        self.name = ""

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name

    def __get__(self, cf: "Crazyflie", owner: type | None = None) -> Any:
        return getattr(getattr(cf, self.service), self.name)


class Crazyflie:
    """One emulated flight controller. Firmware calls are methods with the firmware's snake_case names."""

    def __init__(self, seed: int = 0, model_config: MavModelConfig | FirmwarePlantConfig | None = None,
                 decks: Sequence[str] = ("bcFlow2", "bcLoco"), start: tuple[float, float, float] = (0.0, 0.0, 0.0),
                 require_arming: bool = True, plant: str = "reduced",
                 bounds: tuple[float, float, float, float] | None = None):
        self.scheduler = freertos.Scheduler()
        self.console = Console(self.scheduler)
        self.plant = plant
        if plant == "firmware":
            # the real firmware's commander, supervisor, controller and Kalman estimator over a rigid body
            # (the Bolt build: arming always required); bounds place the Loco anchors around the flown area
            self.stack = FirmwareFlightStack(self.scheduler, self.console.debug_print, seed,
                                             model_config or FirmwarePlantConfig(), start,
                                             bounds or (start[0], start[1], start[0], start[1]))
        elif plant == "reduced":
            self.stack = ReducedFlightStack(self.scheduler, self.console.debug_print, seed, model_config, start, require_arming)
        else:
            raise ValueError("plant must be one of %s, got %r" % (", ".join(PLANTS), plant))
        self.commander = self.stack.commander
        self.supervisor = self.stack.supervisor
        self.model = self.stack.model
        # the firmware's high-level commander (port 8, the trajectory memory): the firmware plant only
        self.high_level = getattr(self.stack, "high_level", None)
        self.registry = LogParamRegistry()
        self.uart2 = None  # attach_uart2(url): the camera's wire on the deck port
        self.decks = _Decks(decks)
        if plant == "reduced":  # the firmware plant serves the firmware's own stateEstimate and supervisor
            self.registry.register_log_group(STATE_ESTIMATE_LOG, self.model.estimate)
            self.registry.register_log_group(SUPERVISOR_LOG, _SupervisorInfo(self.supervisor))
        # the firmware plant: every LOG/PARAM group of the firmware files it compiles, and pm/motor stand-ins
        for group, owner in getattr(self.stack, "log_groups", ()):
            self.registry.register_log_group(group, owner)
        for group, owner in getattr(self.stack, "param_groups", ()):
            self.registry.register_param_group(group, owner)
        self.registry.register_param_group(DECK_PARAM, self.decks)
        self.standins = StandIns()
        for group in STANDIN_PARAM_GROUPS:
            self.registry.register_param_group(group, self.standins)
        self.scheduler.x_task_create(self.stack.stabilizer_task(), "STABILIZER", STABILIZER_TASK_PRI)

    # -- firmware calls one service implements: FreeRTOS, commander, supervisor, UART2, log/param, console --

    x_task_get_tick_count = _Forward("scheduler")
    x_task_create = _Forward("scheduler")
    run_until = _Forward("scheduler")
    commander_set_setpoint = _Forward("commander")
    commander_relax_priority = _Forward("commander")
    commander_get_inactivity_time = _Forward("commander")
    commander_get_active_priority = _Forward("commander")
    supervisor_is_armed = _Forward("supervisor")
    uart2_init = _Forward("uart2")
    uart2_get_data_with_timeout = _Forward("uart2")
    log_get_var_id = _Forward("registry")
    log_get_float = _Forward("registry")
    log_get_uint = _Forward("registry")
    param_get_var_id = _Forward("registry")
    param_get_uint = _Forward("registry")
    param_get_float = _Forward("registry")
    debug_print = _Forward("console")
    event_trigger = _Forward("console")

    # -- supervisor ---------------------------------------------------------------------------------------

    def supervisor_request_arming(self, do_arm: bool) -> bool:
        """supervisorRequestArming(doArm): True when the request was taken (arming needs PRE_FLIGHT)."""
        return self.supervisor.supervisor_request_arming(do_arm, self.x_task_get_tick_count())

    def supervisor_get_info_bitfield(self) -> int:
        """supervisorGetInfoBitfield(): can be armed, is armed, auto-armed, can fly, is flying, is locked (the
        firmware plant: its supervisor.c's own bits)."""
        return self.supervisor.supervisor_get_info_bitfield()

    def platform_config_get_device_type_name(self) -> str:
        """platformConfigGetDeviceTypeName(): the Bolt (arming required) or the CF2 (auto-arming)."""
        return DEVICE_TYPE_NAMES[self.supervisor.require_arming]

    # -- UART2 ----------------------------------------------------------------------------------------------

    def attach_uart2(self, url: str) -> Uart2:
        """Plug a serial wire (a pty slave path) into the deck port's UART2 and start its receive task."""
        self.uart2 = Uart2(self.scheduler, url)
        self.scheduler.x_task_create(self.uart2.rx_task(), "UART2_RX", UART2_RX_TASK_PRI)
        return self.uart2

    def replace_model(self, model: Any) -> None:
        """Fly another MAV model on the reduced plant (a replay drives the MAV from a recorded clip)."""
        if self.plant != "reduced":
            raise ValueError("only the reduced plant's model can be replaced")
        self.stack.model = self.model = model

    def close(self) -> None:
        """Power off: release what the flight stack holds (the firmware plant's library copy)."""
        close = getattr(self.stack, "close", None)
        if close is not None:
            close()
