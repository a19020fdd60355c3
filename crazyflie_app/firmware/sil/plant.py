"""The firmware plant as the emulated Crazyflie's flight stack: the services ``system.Crazyflie`` composes
(``commander``, ``supervisor``, ``model`` and the stabilizer task), here backed by the real firmware in C
(``stack.FirmwareStack``). Their surface is the reduced plant's (``commander.Commander``,
``supervisor.Supervisor``, ``mav_model.MavModel``), so the apps, the harness and the CRTP link do not know
which plant flies.

Time: the stabilizer task wakes every tick (priority 5, above the apps) and runs the C loop up to it; a
call from a task (a setpoint, an arming request) first brings the loop up to the current tick, so the
firmware sees it after the stabilizer step of that tick, as on the Bolt.
"""
from collections.abc import Callable, Sequence

from crazyflie_app.firmware import freertos
from crazyflie_app.firmware.commander import setpoint_t
from crazyflie_app.firmware.logparam import LOG_FLOAT, LOG_UINT16, log_add, log_group
from crazyflie_app.firmware.sil.stack import (CRASH_REASONS, SUPERVISOR_STATE_NAMES, WATCHDOG_STATES,
                                              FirmwarePlantConfig, FirmwareStack)
from crazyflie_app.firmware.sil.tables import read_tables

Console = Callable[[str, str], None]  # (module, text): the Crazyflie's DEBUG_PRINT


class FirmwareClock:
    """Brings the C loop up to the scheduler's tick and passes on what happened: console lines and
    supervisor state changes."""

    def __init__(self, stack: FirmwareStack, scheduler: freertos.Scheduler, console: Console,
                 on_tick: Callable[[int], None]):
        self.stack, self.scheduler, self.console, self.on_tick = stack, scheduler, console, on_tick

    def sync(self) -> int:
        now = self.scheduler.x_task_get_tick_count()
        if now > self.stack.tick:
            self.stack.advance_to(now)
            for module, text in self.stack.console_lines():
                self.console(module, text)
            self.on_tick(now)
        return now


class FirmwareCommander:
    """commander.c through the stack; ``listeners`` are telemetry taps, as on the reduced plant's."""

    def __init__(self, stack: FirmwareStack, clock: FirmwareClock):
        self.stack, self.clock = stack, clock
        self.listeners = []
        self.rejected = 0
        self._last = setpoint_t()

    def commander_set_setpoint(self, sp: setpoint_t, priority: int) -> bool:
        now = self.clock.sync()
        if not self.stack.set_setpoint(sp, priority):
            self.rejected += 1
            return False
        sp.timestamp = now
        self._last = sp.copy()
        for listener in self.listeners:
            listener(self._last, priority)
        return True

    def commander_relax_priority(self) -> None:
        self.clock.sync()
        self.stack.lib.sil_commander_relax_priority()

    def commander_get_setpoint(self) -> setpoint_t:
        """The last setpoint this commander took (the one commanderGetSetpoint peeks at)."""
        return self._last

    def commander_get_active_priority(self) -> int:
        self.clock.sync()
        return self.stack.lib.sil_commander_get_active_priority()

    def commander_get_inactivity_time(self) -> int:
        self.clock.sync()
        return self.stack.lib.sil_commander_get_inactivity_time()


class FirmwareSupervisor:
    """supervisor.c's state, seen from the host: its name, the transitions with their ticks, arming."""

    require_arming = True  # the Bolt build (bolt_defconfig: CONFIG_MOTORS_REQUIRE_ARMING)

    def __init__(self, stack: FirmwareStack, clock: FirmwareClock):
        self.stack, self.clock = stack, clock
        self.events = []  # (tick, state entered)
        self.arming_events = []  # (tick, "armed" | "disarmed")
        self._state = self.stack.status.supervisor_state
        self._armed = bool(self.stack.status.armed)

    @property
    def state(self) -> str:
        return SUPERVISOR_STATE_NAMES[self.stack.status.supervisor_state]

    @property
    def state_index(self) -> int:
        """supervisorState_t"""
        return self.stack.status.supervisor_state

    @property
    def watchdog_events(self) -> list[tuple[int, str]]:
        """Level-outs, free falls, locks and crashes so far (a healthy flight has none)."""
        return [e for e in self.events if e[1] in WATCHDOG_STATES]

    def observe(self, tick: int) -> None:
        status = self.stack.status
        if status.supervisor_state != self._state:
            self._state = status.supervisor_state
            self.events.append((tick, SUPERVISOR_STATE_NAMES[self._state]))
        if bool(status.armed) != self._armed:
            self._armed = bool(status.armed)
            self.arming_events.append((tick, "armed" if self._armed else "disarmed"))

    def supervisor_request_arming(self, do_arm: bool, tick: int = 0) -> bool:
        self.clock.sync()
        taken = bool(self.stack.lib.sil_supervisor_request_arming(1 if do_arm else 0))
        self.observe(tick)
        return taken

    def supervisor_is_armed(self) -> bool:
        self.clock.sync()
        return bool(self.stack.status.armed)

    def supervisor_get_info_bitfield(self) -> int:
        """supervisor.c's own supervisorGetInfoBitfield()."""
        self.clock.sync()
        return self.stack.lib.sil_supervisor_info_bitfield()


class FirmwareHighLevel:
    """The firmware's high-level commander (crtp_commander_high_level.c, planner.c, pptraj.c): a client's
    port-8 commands and its trajectory memory, acted on at the current tick (the stabilizer loop flies its
    setpoints at COMMANDER_PRIORITY_HIGHLEVEL)."""

    def __init__(self, stack: FirmwareStack, clock: FirmwareClock):
        self.stack, self.clock = stack, clock

    def command(self, payload: bytes) -> int:
        """handleCommand(data[0], &data[1]) -> 0 or the errno the firmware answers with."""
        self.clock.sync()
        return self.stack.high_level_command(payload)

    @property
    def memory_size(self) -> int:
        return self.stack.trajectory_memory_size()

    def memory_write(self, address: int, data: bytes) -> bool:
        self.clock.sync()
        return self.stack.trajectory_memory_write(address, data)

    def memory_read(self, address: int, length: int) -> bytes | None:
        return self.stack.trajectory_memory_read(address, length)


class FirmwareModel:
    """The plant's truth and the firmware's stateEstimate (both written by the C loop every tick)."""

    def __init__(self, stack: FirmwareStack):
        self.stack = stack
        self.truth = stack.truth
        self.estimate = stack.estimate

    @property
    def crashed(self) -> bool:
        return bool(self.stack.status.crashed)

    @property
    def crash_reason(self) -> str | None:
        return CRASH_REASONS.get(self.stack.status.crashed)

    @property
    def status(self):
        return self.stack.status

    @property
    def battery_v(self) -> float:
        return self.stack.status.battery_v

    def motor_pwm(self, index: int) -> int:
        """The ratio the stabilizer set motor ``index`` to, 0-65535 (motorsGetRatio)."""
        return int(round(self.stack.status.motor_ratio[index] * 65535))

    m1 = property(lambda self: self.motor_pwm(0))
    m2 = property(lambda self: self.motor_pwm(1))
    m3 = property(lambda self: self.motor_pwm(2))
    m4 = property(lambda self: self.motor_pwm(3))


# stand-ins for log variables of firmware files this build does not compile (pm_stm32f4.c, motors.c), which
# clients look for (cfclient's battery and motor gauges, cflib's basiclog example), read from the plant
PM_LOG = log_group("pm", [log_add(LOG_FLOAT, "vbat", "battery_v", "V", "battery voltage")])
MOTOR_LOG = log_group("motor", [log_add(LOG_UINT16, name, name, "", "motor %s ratio, 0-65535" % name.upper())
                                for name in ("m1", "m2", "m3", "m4")])


class FirmwareFlightStack:
    """commander, supervisor, model and stabilizer task of the firmware plant, for ``system.Crazyflie``."""

    def __init__(self, scheduler: freertos.Scheduler, console: Console, seed: int, config: FirmwarePlantConfig,
                 start: Sequence[float], bounds: tuple[float, float, float, float]):
        self.stack = FirmwareStack(config, seed, start, bounds)
        self.clock = FirmwareClock(self.stack, scheduler, console, self._on_tick)
        self.commander = FirmwareCommander(self.stack, self.clock)
        self.supervisor = FirmwareSupervisor(self.stack, self.clock)
        self.model = FirmwareModel(self.stack)
        self.high_level = FirmwareHighLevel(self.stack, self.clock)
        # the firmware's own LOG/PARAM groups (every file compiled into the library), then the stand-ins
        self.tables = read_tables(self.stack.lib, lambda: self.stack.tick)
        self.log_groups = [(group, self.tables.owner) for group in self.tables.log_groups] + [
            (PM_LOG, self.model), (MOTOR_LOG, self.model)]
        self.param_groups = [(group, self.tables.owner) for group in self.tables.param_groups]

    def _on_tick(self, tick: int) -> None:
        self.supervisor.observe(tick)

    def stabilizer_task(self) -> freertos.Task:
        while True:
            self.clock.sync()
            yield freertos.v_task_delay(1)

    def close(self) -> None:
        self.tables.owner.freeze()
        self.stack.close()
