"""supervisor.c / supervisor_state_machine.c: arming and the setpoint watchdog (firmware >= 2023.06).

Arming (``CONFIG_MOTORS_REQUIRE_ARMING``, set in the Bolt's ``bolt_defconfig``; ``require_arming=True``, the
default here): the MAV boots in PRE_FLIGHT (pre-flight checks passed, can arm) with the motors not allowed
to run, so every setpoint is replaced by the null one. ``supervisor_request_arming(True)`` (the app, or the
client's arming command) arms it: READY_TO_FLY, and the first fresh non-null setpoint makes it FLYING. The
firmware's disarm timeouts apply: armed but not flying for more than PREFLIGHT_TIMEOUT_MS (30 s) -> disarmed
("Disarming", back to PRE_FLIGHT); LANDED for more than LANDING_TIMEOUT_MS (3 s) -> disarmed; a request to
disarm while flying cuts the motors. With ``require_arming=False`` (the CF2 default, AUTO_ARMING) the
supervisor arms itself whenever it can, as the firmware does.

While the MAV flies, the age of the last accepted setpoint is watched:
  age > 500 ms  (COMMANDER_WDT_TIMEOUT_STABILIZE) -> WARNING_LEVEL_OUT: x/y disabled, attitude level, yaw rate 0,
                z kept as commanded; a fresh setpoint brings it back to FLYING;
  age > 2000 ms (COMMANDER_WDT_TIMEOUT_SHUTDOWN)  -> EXCEPTION_FREE_FALL -> LOCKED: motors off, sticky until reboot.
A null setpoint (all modes disabled, thrust 0) stops the motors; after IS_FLYING_HYSTERESIS_THRESHOLD ms of
motors off the MAV counts as LANDED and the watchdog no longer applies.

``next_event_tick()`` gives the exact tick of the next threshold crossing, so the stabilizer can step at its
100 Hz position-loop rate and still switch state on the very tick the firmware would. Not modelled: the
ARMING spin-up state (without bidirectional DShot the firmware passes it on the next tick), tumble, crash
and emergency stop.
"""
from collections.abc import Callable

from crazyflie_app.firmware.commander import modeAbs, modeDisable, modeVelocity, setpoint_t

COMMANDER_WDT_TIMEOUT_STABILIZE = 500  # ms
COMMANDER_WDT_TIMEOUT_SHUTDOWN = 2000  # ms
IS_FLYING_HYSTERESIS_THRESHOLD = 2000  # ms
PREFLIGHT_TIMEOUT_MS = 30000  # platform_defaults.h: armed this long without flying -> disarmed
LANDING_TIMEOUT_MS = 3000  # platform_defaults.h: landed this long -> disarmed

PRE_FLIGHT = "PRE_FLIGHT"
FLYING = "FLYING"
WARNING_LEVEL_OUT = "WARNING_LEVEL_OUT"
LANDED = "LANDED"
LOCKED = "LOCKED"
READY_TO_FLY = "READY_TO_FLY"
SUPERVISOR_STATES = (PRE_FLIGHT, FLYING, WARNING_LEVEL_OUT, LANDED, LOCKED, READY_TO_FLY)
# supervisor.c's info bitfield (the CRTP supervisor port's answer; supervisorGetInfoBitfield)
SUPERVISOR_INFO_CAN_BE_ARMED, SUPERVISOR_INFO_IS_ARMED, SUPERVISOR_INFO_AUTO_ARMED = 0x01, 0x02, 0x04
SUPERVISOR_INFO_CAN_FLY, SUPERVISOR_INFO_IS_FLYING, SUPERVISOR_INFO_IS_LOCKED = 0x08, 0x10, 0x40


class Supervisor:
    def __init__(self, require_arming: bool = True, console: Callable[[str], None] | None = None):
        self.state = PRE_FLIGHT
        self.require_arming = bool(require_arming)
        self.armed = not self.require_arming
        self.events = []  # (tick, state entered)
        self.arming_events = []  # (tick, "armed" | "disarmed")
        self._console = console  # callable(text): the firmware's DEBUG_PRINT lines
        self._motors_off_since = None
        self._armed_since = None
        self._landed_since = None

    @property
    def state_index(self) -> int:
        return SUPERVISOR_STATES.index(self.state)

    @property
    def watchdog_events(self) -> list[tuple[int, str]]:
        """Level-outs and locks so far (a healthy flight has none)."""
        return [e for e in self.events if e[1] in (WARNING_LEVEL_OUT, LOCKED)]

    def _print(self, text: str) -> None:
        if self._console is not None:
            self._console(text)

    def _enter(self, tick, state):
        if state != self.state:
            self.state = state
            self.events.append((tick, state))
            if state == READY_TO_FLY:
                self._armed_since = tick
                self._print("Ready to fly")
            if state == LANDED:
                self._landed_since = tick
            if state == LOCKED:
                self._print("Locked, reboot required")
                if self.armed:  # postTransitionActions: every state but the flying ones disarms
                    self.armed = False
                    self.arming_events.append((tick, "disarmed"))

    def _disarm(self, tick):
        """Back to PRE_FLIGHT unarmed (the firmware's Reset / PreFlChecksNotPassed path)."""
        if self.require_arming:
            if self.armed:
                self.arming_events.append((tick, "disarmed"))
            self.armed = False
            self._print("Disarming")
        self._motors_off_since = None
        self._enter(tick, PRE_FLIGHT)

    def supervisor_can_arm(self) -> bool:
        return self.state == PRE_FLIGHT

    def supervisor_is_armed(self) -> bool:
        return self.armed

    def supervisor_request_arming(self, do_arm: bool, tick: int = 0) -> bool:
        """supervisorRequestArming(doArm): False if arming is asked for where it cannot be (not PRE_FLIGHT)."""
        do_arm = bool(do_arm)
        if do_arm == self.armed:
            return True
        if do_arm and not self.supervisor_can_arm():
            return False
        self.armed = do_arm
        self.arming_events.append((tick, "armed" if do_arm else "disarmed"))
        return True

    def supervisor_update(self, now: int, setpoint: setpoint_t) -> None:
        """One supervisor step at tick ``now`` with the setpoint the commander holds."""
        if self.state == LOCKED:
            return
        age = now - setpoint.timestamp
        fresh = age <= COMMANDER_WDT_TIMEOUT_STABILIZE and not setpoint.is_null()
        if self.state == PRE_FLIGHT:
            if not self.armed:
                return  # motors not allowed: every setpoint is the null one
            if self.require_arming:
                self._enter(now, READY_TO_FLY)
            elif fresh:
                self._enter(now, FLYING)
                return
        if self.state == READY_TO_FLY:
            if not self.armed or now - self._armed_since > PREFLIGHT_TIMEOUT_MS:
                self._disarm(now)
            elif fresh:
                self._motors_off_since = None
                self._enter(now, FLYING)
            return
        if self.state == LANDED:
            if not self.armed or (self.require_arming and now - self._landed_since > LANDING_TIMEOUT_MS):
                self._disarm(now)
            elif fresh:
                self._motors_off_since = None
                self._enter(now, FLYING)
            return
        # FLYING or WARNING_LEVEL_OUT
        if not self.armed:
            self._disarm(now)
            return
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

    def next_event_tick(self, now: int, setpoint: setpoint_t) -> int | None:
        """The first tick after ``now`` at which supervisor_update could change state (None if never)."""
        candidates = []
        if self.state in (FLYING, WARNING_LEVEL_OUT):
            candidates += [setpoint.timestamp + COMMANDER_WDT_TIMEOUT_STABILIZE + 1,
                           setpoint.timestamp + COMMANDER_WDT_TIMEOUT_SHUTDOWN + 1]
            if self._motors_off_since is not None:
                candidates.append(self._motors_off_since + IS_FLYING_HYSTERESIS_THRESHOLD + 1)
        elif self.state == READY_TO_FLY:
            candidates.append(self._armed_since + PREFLIGHT_TIMEOUT_MS + 1)
        elif self.state == LANDED and self.require_arming:
            candidates.append(self._landed_since + LANDING_TIMEOUT_MS + 1)
        later = [c for c in candidates if c > now]
        return min(later) if later else None

    def supervisor_get_info_bitfield(self) -> int:
        """supervisorGetInfoBitfield(): can be armed, is armed, auto-armed, can fly, is flying, is locked (the
        tumbled, crashed and high-level-commander bits stay 0: this supervisor does not model them)."""
        return ((SUPERVISOR_INFO_CAN_BE_ARMED if self.supervisor_can_arm() else 0)
                | (SUPERVISOR_INFO_IS_ARMED if self.supervisor_is_armed() else 0)
                | (SUPERVISOR_INFO_AUTO_ARMED if not self.require_arming else 0)
                | (SUPERVISOR_INFO_CAN_FLY if self.supervisor_are_motors_allowed_to_run() else 0)
                | (SUPERVISOR_INFO_IS_FLYING if self.state in (FLYING, WARNING_LEVEL_OUT) else 0)
                | (SUPERVISOR_INFO_IS_LOCKED if self.state == LOCKED else 0))

    def supervisor_can_fly(self) -> bool:
        return self.state != LOCKED

    def supervisor_are_motors_allowed_to_run(self) -> bool:
        return self.state in (READY_TO_FLY, FLYING, WARNING_LEVEL_OUT, LANDED)

    def motors_running(self, setpoint: setpoint_t) -> bool:
        return self.state in (FLYING, WARNING_LEVEL_OUT) and not (self.state == FLYING and setpoint.is_null())

    def supervisor_override_setpoint(self, setpoint: setpoint_t) -> setpoint_t:
        """The setpoint the controller actually gets: the null one while motors are not allowed to run,
        level-out rewrites x/y/attitude and keeps z."""
        if self.state == PRE_FLIGHT and self.require_arming:
            return setpoint.__class__()  # memcpy(setpoint, &nullSetpoint): unarmed, motors stay off
        if self.state != WARNING_LEVEL_OUT:
            return setpoint
        sp = setpoint.copy()
        sp.mode.x = sp.mode.y = modeDisable
        sp.mode.roll = sp.mode.pitch = modeAbs
        sp.attitude.roll = sp.attitude.pitch = 0.0
        sp.mode.yaw = modeVelocity
        sp.attitudeRate.yaw = 0.0
        return sp
