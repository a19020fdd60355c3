"""The emulated Crazyflie: scheduler, commander, supervisor, stabilizer task, estimate, log/param, console.

``Crazyflie(seed=..., model_config=..., decks=...)`` boots the services an app needs; ``x_task_create`` adds
app tasks; ``run_until(tick)`` advances the whole system. The stabilizer task (priority 5, the highest) runs
at the 100 Hz position-loop rate and additionally wakes on the exact tick of any watchdog threshold, so
level-out and lock happen when the firmware would, without stepping Python at 1 kHz.
"""
from collections.abc import Sequence
from typing import Any

from crazyflie_app.firmware import freertos
from crazyflie_app.firmware.commander import Commander
from crazyflie_app.firmware.logparam import (LOG_FLOAT, LOG_UINT8, PARAM_UINT8, LogParamRegistry, log_add,
                                              log_group, param_add, param_group)
from crazyflie_app.firmware.mav_model import MavModel, MavModelConfig
from crazyflie_app.firmware.supervisor import FLYING, LOCKED, SUPERVISOR_STATES, WARNING_LEVEL_OUT, Supervisor
from crazyflie_app.firmware.uart2 import Uart2

STABILIZER_TASK_PRI = 5
UART2_RX_TASK_PRI = 5  # stands in for the USART2 receive interrupt
POSITION_RATE_HZ = 100  # RATE_100_HZ: the position controller's rate
STABILIZER_PERIOD_MS = 1000 // POSITION_RATE_HZ
# platform_bolt.c / platform_cf2.c: the name the platform service gives a client (require_arming: the Bolt)
DEVICE_TYPE_NAMES = {True: "Crazyflie Bolt 1.1", False: "Crazyflie 2.1"}
# supervisor.c's info bitfield (the supervisor.info log variable of the firmware, and the CRTP supervisor port)
SUPERVISOR_INFO_CAN_BE_ARMED, SUPERVISOR_INFO_IS_ARMED, SUPERVISOR_INFO_AUTO_ARMED = 0x01, 0x02, 0x04
SUPERVISOR_INFO_CAN_FLY, SUPERVISOR_INFO_IS_FLYING, SUPERVISOR_INFO_IS_LOCKED = 0x08, 0x10, 0x40

STATE_ESTIMATE_LOG = log_group("stateEstimate", [
    log_add(LOG_FLOAT, "x", "x", "m", "estimated position, global frame"),
    log_add(LOG_FLOAT, "y", "y", "m", "estimated position, global frame"),
    log_add(LOG_FLOAT, "z", "z", "m", "estimated height"),
    log_add(LOG_FLOAT, "vx", "vx", "m/s", "estimated velocity, global frame"),
    log_add(LOG_FLOAT, "vy", "vy", "m/s", "estimated velocity, global frame"),
    log_add(LOG_FLOAT, "vz", "vz", "m/s", "estimated vertical velocity"),
    log_add(LOG_FLOAT, "yaw", "yaw", "deg", "estimated yaw, counter-clockwise"),
])
SUPERVISOR_LOG = log_group("supervisor", [
    log_add(LOG_UINT8, "info", "state_index", "", "supervisor state: " + ", ".join(
        "%d %s" % (i, s) for i, s in enumerate(SUPERVISOR_STATES))),
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
        return SUPERVISOR_STATES.index(self._supervisor.state)


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

    def __init__(self, seed: int = 0, model_config: MavModelConfig | None = None,
                 decks: Sequence[str] = ("bcFlow2", "bcLoco"), start: tuple[float, float, float] = (0.0, 0.0, 0.0),
                 require_arming: bool = True):
        self.scheduler = freertos.Scheduler()
        self.commander = Commander(self.scheduler)
        self.console = Console(self.scheduler)
        # the Bolt (bolt_defconfig: CONFIG_MOTORS_REQUIRE_ARMING=y); require_arming=False: the CF2's auto-arming
        self.supervisor = Supervisor(require_arming, console=lambda text: self.console.debug_print("SUP", text))
        self.model = MavModel(model_config, seed=seed, start=start)
        self.registry = LogParamRegistry()
        self.uart2 = None  # attach_uart2(url): the camera's wire on the deck port
        self.decks = _Decks(decks)
        self.registry.register_log_group(STATE_ESTIMATE_LOG, self.model.estimate)
        self.registry.register_log_group(SUPERVISOR_LOG, _SupervisorInfo(self.supervisor))
        self.registry.register_param_group(DECK_PARAM, self.decks)
        self._last_physics_tick = 0
        self._active_setpoint = self.commander.commander_get_setpoint()
        self._motors_on = False
        self.scheduler.x_task_create(self._stabilizer_task(), "STABILIZER", STABILIZER_TASK_PRI)

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
        tumbled, crashed and high-level-commander bits stay 0: this supervisor does not model them)."""
        sup = self.supervisor
        bits = ((SUPERVISOR_INFO_CAN_BE_ARMED if sup.supervisor_can_arm() else 0)
                | (SUPERVISOR_INFO_IS_ARMED if sup.supervisor_is_armed() else 0)
                | (SUPERVISOR_INFO_AUTO_ARMED if not sup.require_arming else 0)
                | (SUPERVISOR_INFO_CAN_FLY if sup.supervisor_are_motors_allowed_to_run() else 0)
                | (SUPERVISOR_INFO_IS_FLYING if sup.state in (FLYING, WARNING_LEVEL_OUT) else 0)
                | (SUPERVISOR_INFO_IS_LOCKED if sup.state == LOCKED else 0))
        return bits

    def platform_config_get_device_type_name(self) -> str:
        """platformConfigGetDeviceTypeName(): the Bolt (arming required) or the CF2 (auto-arming)."""
        return DEVICE_TYPE_NAMES[self.supervisor.require_arming]

    # -- UART2 ----------------------------------------------------------------------------------------------

    def attach_uart2(self, url: str) -> Uart2:
        """Plug a serial wire (a pty slave path) into the deck port's UART2 and start its receive task."""
        self.uart2 = Uart2(self.scheduler, url)
        self.scheduler.x_task_create(self.uart2.rx_task(), "UART2_RX", UART2_RX_TASK_PRI)
        return self.uart2

    # -- the stabilizer -----------------------------------------------------------------------------------

    def _stabilizer_task(self):
        """commanderGetSetpoint -> supervisorUpdate -> override -> controller + plant, every 10 ms or on a
        watchdog threshold, whichever comes first."""
        while True:
            now = self.scheduler.x_task_get_tick_count()
            dt = (now - self._last_physics_tick) / 1000.0
            self._last_physics_tick = now
            setpoint = self.commander.commander_get_setpoint()
            # the plant ran under the previous state up to now; then the supervisor looks at the new age
            self.model.step(dt, self._active_setpoint, self._motors_on)
            self.supervisor.supervisor_update(now, setpoint)
            self._active_setpoint = self.supervisor.supervisor_override_setpoint(setpoint)
            self._motors_on = self.supervisor.motors_running(setpoint)
            delay = STABILIZER_PERIOD_MS
            event = self.supervisor.next_event_tick(now, setpoint)
            if event is not None:
                delay = min(delay, event - now)
            yield freertos.v_task_delay(delay)

