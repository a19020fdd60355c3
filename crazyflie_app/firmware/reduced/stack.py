"""The reduced plant's flight stack: what the stabilizer task of the emulated Crazyflie runs with
``plant="reduced"``."""
from collections.abc import Callable

from crazyflie_app.firmware import freertos
from crazyflie_app.firmware.commander import Commander
from crazyflie_app.firmware.reduced.mav_model import MavModel, MavModelConfig
from crazyflie_app.firmware.supervisor import Supervisor

POSITION_RATE_HZ = 100  # RATE_100_HZ: the position controller's rate
STABILIZER_PERIOD_MS = 1000 // POSITION_RATE_HZ


class ReducedFlightStack:
    """The default plant: the Python commander and supervisor and the reduced closed-loop MAV model
    (commander.py, supervisor.py, mav_model.py), stepped by a stabilizer task at the position loop's rate."""

    def __init__(self, scheduler: freertos.Scheduler, console: Callable[[str, str], None], seed: int,
                 model_config: MavModelConfig | None, start: tuple[float, float, float], require_arming: bool):
        self.scheduler = scheduler
        self.commander = Commander(scheduler)
        # the Bolt (bolt_defconfig: CONFIG_MOTORS_REQUIRE_ARMING=y); require_arming=False: the CF2's auto-arming
        self.supervisor = Supervisor(require_arming, console=lambda text: console("SUP", text))
        self.model = MavModel(model_config, seed=seed, start=start)
        self._last_physics_tick = 0
        self._active_setpoint = self.commander.commander_get_setpoint()
        self._motors_on = False

    def stabilizer_task(self) -> freertos.Task:
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
