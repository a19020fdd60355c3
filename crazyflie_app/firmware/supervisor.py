"""supervisor.c / supervisor_state_machine.c: the setpoint watchdog (firmware >= 2023.06).

While the MAV flies, the age of the last accepted setpoint is watched:
  age > 500 ms  (COMMANDER_WDT_TIMEOUT_STABILIZE) -> WARNING_LEVEL_OUT: x/y disabled, attitude level, yaw rate 0,
                z kept as commanded; a fresh setpoint brings it back to FLYING;
  age > 2000 ms (COMMANDER_WDT_TIMEOUT_SHUTDOWN)  -> EXCEPTION_FREE_FALL -> LOCKED: motors off, sticky until reboot.
A null setpoint (all modes disabled, thrust 0) stops the motors; after IS_FLYING_HYSTERESIS_THRESHOLD ms of
motors off the MAV counts as LANDED and the watchdog no longer applies.

``next_event_tick()`` gives the exact tick of the next threshold crossing, so the stabilizer can step at its
100 Hz position-loop rate and still switch state on the very tick the firmware would.
"""
from crazyflie_app.firmware.commander import modeAbs, modeDisable, modeVelocity

COMMANDER_WDT_TIMEOUT_STABILIZE = 500  # ms
COMMANDER_WDT_TIMEOUT_SHUTDOWN = 2000  # ms
IS_FLYING_HYSTERESIS_THRESHOLD = 2000  # ms

PRE_FLIGHT = "PRE_FLIGHT"
FLYING = "FLYING"
WARNING_LEVEL_OUT = "WARNING_LEVEL_OUT"
LANDED = "LANDED"
LOCKED = "LOCKED"
SUPERVISOR_STATES = (PRE_FLIGHT, FLYING, WARNING_LEVEL_OUT, LANDED, LOCKED)


class Supervisor(object):
    def __init__(self):
        self.state = PRE_FLIGHT
        self.events = []  # (tick, state entered)
        self._motors_off_since = None

    @property
    def watchdog_events(self):
        """Level-outs and locks so far (a healthy flight has none)."""
        return [e for e in self.events if e[1] in (WARNING_LEVEL_OUT, LOCKED)]

    def _enter(self, tick, state):
        if state != self.state:
            self.state = state
            self.events.append((tick, state))

    def supervisor_update(self, now, setpoint):
        """One supervisor step at tick ``now`` with the setpoint the commander holds."""
        if self.state == LOCKED:
            return
        age = now - setpoint.timestamp
        flying = self.state in (FLYING, WARNING_LEVEL_OUT)
        if flying:
            if age > COMMANDER_WDT_TIMEOUT_SHUTDOWN:
                self._enter(now, LOCKED)  # via EXCEPTION_FREE_FALL, which locks at once
                return
            if age > COMMANDER_WDT_TIMEOUT_STABILIZE:
                self._enter(now, WARNING_LEVEL_OUT)
                return
            self._enter(now, FLYING)
            if setpoint.is_null():
                if self._motors_off_since is None:
                    self._motors_off_since = now
                if now - self._motors_off_since > IS_FLYING_HYSTERESIS_THRESHOLD:
                    self._enter(now, LANDED)
            else:
                self._motors_off_since = None
        elif age <= COMMANDER_WDT_TIMEOUT_STABILIZE and not setpoint.is_null():
            self._motors_off_since = None
            self._enter(now, FLYING)

    def next_event_tick(self, now, setpoint):
        """The first tick after ``now`` at which supervisor_update could change state (None if never)."""
        if self.state not in (FLYING, WARNING_LEVEL_OUT):
            return None
        candidates = [setpoint.timestamp + COMMANDER_WDT_TIMEOUT_STABILIZE + 1,
                      setpoint.timestamp + COMMANDER_WDT_TIMEOUT_SHUTDOWN + 1]
        if self._motors_off_since is not None:
            candidates.append(self._motors_off_since + IS_FLYING_HYSTERESIS_THRESHOLD + 1)
        later = [c for c in candidates if c > now]
        return min(later) if later else None

    def supervisor_can_fly(self):
        return self.state != LOCKED

    def motors_running(self, setpoint):
        return self.state in (FLYING, WARNING_LEVEL_OUT) and not (self.state == FLYING and setpoint.is_null())

    def supervisor_override_setpoint(self, setpoint):
        """The setpoint the controller actually gets (level-out rewrites x/y/attitude, keeps z)."""
        if self.state != WARNING_LEVEL_OUT:
            return setpoint
        sp = setpoint.copy()
        sp.mode.x = sp.mode.y = modeDisable
        sp.mode.roll = sp.mode.pitch = modeAbs
        sp.attitude.roll = sp.attitude.pitch = 0.0
        sp.mode.yaw = modeVelocity
        sp.attitudeRate.yaw = 0.0
        return sp
