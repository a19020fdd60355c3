"""commander.h / commander.c: setpoint_t and the priority rule for who may fly the MAV.

``commander_set_setpoint(sp, priority)`` takes the setpoint only if ``priority`` is at or above the current
one; on accept it stamps ``sp.timestamp`` with the tick count (the caller's struct is mutated, as in C) and
stores a deep copy in the 1-deep queue the stabilizer peeks at. The stored priority never decays by itself:
``commander_relax_priority()`` hands control back to the lowest level.
"""
from dataclasses import dataclass, field, replace
from typing import Any

# stab_mode_t
modeDisable = 0
modeAbs = 1
modeVelocity = 2

COMMANDER_PRIORITY_DISABLE = 0
COMMANDER_PRIORITY_LOWEST = 1
COMMANDER_PRIORITY_HIGHLEVEL = 1
COMMANDER_PRIORITY_CRTP = 2
COMMANDER_PRIORITY_EXTRX = 3


@dataclass
class Vec3:
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0


@dataclass
class Attitude:
    """Degrees (attitude) or degrees per second (attitudeRate), as in stabilizer_types.h."""
    roll: float = 0.0
    pitch: float = 0.0
    yaw: float = 0.0


@dataclass
class SetpointMode:
    x: int = modeDisable
    y: int = modeDisable
    z: int = modeDisable
    roll: int = modeDisable
    pitch: int = modeDisable
    yaw: int = modeDisable
    quat: int = modeDisable


@dataclass
class setpoint_t:  # noqa: N801 - the firmware's type name
    """The fields of stabilizer_types.h setpoint_t that the app layer uses. Zero-initialised = motors off."""
    timestamp: int = 0  # ticks, written by the commander on accept
    attitude: Attitude = field(default_factory=Attitude)
    attitudeRate: Attitude = field(default_factory=Attitude)  # noqa: N815
    thrust: float = 0.0
    position: Vec3 = field(default_factory=Vec3)
    velocity: Vec3 = field(default_factory=Vec3)
    acceleration: Vec3 = field(default_factory=Vec3)
    velocity_body: bool = False
    mode: SetpointMode = field(default_factory=SetpointMode)

    def memset_zero(self) -> None:
        """memset(&sp, 0, sizeof(sp)): every field back to zero / modeDisable."""
        self.__init__()

    def copy(self) -> "setpoint_t":
        """A deep copy (the commander's queue holds a copy, not the caller's struct); faster than deepcopy."""
        return replace(self, attitude=replace(self.attitude), attitudeRate=replace(self.attitudeRate),
                       position=replace(self.position), velocity=replace(self.velocity),
                       acceleration=replace(self.acceleration), mode=replace(self.mode))

    def is_null(self) -> bool:
        """All axes disabled and no thrust: the null setpoint that stops the motors."""
        m = self.mode
        return (m.x == m.y == m.z == m.roll == m.pitch == m.yaw == m.quat == modeDisable
                and self.thrust == 0.0)


class Commander:
    """The commander's state: current priority and the last accepted setpoint."""

    def __init__(self, clock: Any):
        self._clock = clock  # anything with x_task_get_tick_count()
        self._setpoint = setpoint_t()
        self._priority = COMMANDER_PRIORITY_DISABLE
        self.listeners = []  # callables(setpoint_copy, priority): telemetry taps, not firmware
        self.rejected = 0  # setpoints refused for low priority

    def commander_set_setpoint(self, sp: setpoint_t, priority: int) -> bool:
        """Accept ``sp`` iff ``priority`` >= the current priority; return True when accepted."""
        if priority < self._priority:
            self.rejected += 1
            return False
        sp.timestamp = self._clock.x_task_get_tick_count()
        self._setpoint = sp.copy()
        self._priority = priority
        for listener in self.listeners:
            listener(self._setpoint, priority)
        return True

    def commander_relax_priority(self) -> None:
        """Let lower-priority sources (radio, high-level commander) command again."""
        self._priority = COMMANDER_PRIORITY_LOWEST

    def commander_get_setpoint(self) -> setpoint_t:
        """What the stabilizer peeks at each step (a copy: consumers must not alter the queue)."""
        return self._setpoint

    def commander_get_active_priority(self) -> int:
        return self._priority

    def commander_get_inactivity_time(self) -> int:
        """Ticks since the last accepted setpoint."""
        return self._clock.x_task_get_tick_count() - self._setpoint.timestamp
