"""crtp_commander.c, crtp_commander_rpyt.c and crtp_commander_generic.c (ports 3 and 7): a client's setpoints.

Every decoded setpoint goes to ``commander_set_setpoint(sp, COMMANDER_PRIORITY_CRTP)``, so the commander's
priority rule decides, as on the MAV: while the ForaNav app flies (COMMANDER_PRIORITY_EXTRX) a client's
setpoints are refused.

    port 3 ch 0  legacy roll/pitch/yaw-rate/thrust [roll f, pitch f, yawrate f, thrust u16], decoded with the
                 firmware's default flight modes (roll and pitch angle, yaw rate, X mode; no alt-hold,
                 pos-hold or pos-set: this emulation has no ``flightmode`` params), thrust locked until a
                 zero thrust arrives and below 1000 taken as 0
    port 7 ch 0  generic setpoint [type, payload]: stop (0), legacy velocity-world (1), legacy z-distance (2),
                 CPPM emulation (3), alt-hold (4), legacy hover (5), position (7), velocity-world (8),
                 z-distance (9), hover (10), manual (11); an unknown type is the null setpoint, as in the
                 firmware. Not served: full-state (6), which needs the attitude quaternion this setpoint_t
                 does not carry
    port 7 ch 1  meta command [0, u32]: notifySetpointsStop -> commanderRelaxPriority()

A payload of the wrong size, which the firmware ASSERTs on, is dropped and counted instead.
"""
import struct
from collections.abc import Callable

from crazyflie_app.firmware.commander import (COMMANDER_PRIORITY_CRTP, COMMANDER_PRIORITY_DISABLE, modeAbs,
                                              modeDisable, modeVelocity, setpoint_t)
from crazyflie_app.firmware.crtp.packet import (CRTP_PORT_SETPOINT, CrtpPacket, MalformedPacket, Unserved,
                                                field_u8)

SET_SETPOINT_CHANNEL, META_COMMAND_CHANNEL = 0, 1
META_NOTIFY_SETPOINTS_STOP = 0
MIN_THRUST, MAX_THRUST = 1000, 60000
UINT16_MAX = 65535
FULL_STATE_TYPE = 6
CPPM_MAX_AUX_CHANNELS = 10
# crtp_commander_generic.c's CPPM scaling (the cppm params' defaults)
CPPM_ANGLE_MAX_DEG, CPPM_YAW_RATE_MAX_DPS = 50.0, 400.0


def _floats(payload: bytes, count: int, tail: str = "") -> tuple:
    fmt = "<%df%s" % (count, tail)
    if len(payload) != struct.calcsize(fmt):
        raise MalformedPacket("setpoint payload of %d bytes, expected %d" % (len(payload), struct.calcsize(fmt)))
    return struct.unpack(fmt, payload)


def _roll_pitch_abs(sp: setpoint_t, roll: float, pitch: float) -> None:
    sp.mode.roll = sp.mode.pitch = modeAbs
    sp.attitude.roll, sp.attitude.pitch = roll, pitch


def _yaw_rate(sp: setpoint_t, rate: float) -> None:
    sp.mode.yaw = modeVelocity
    sp.attitudeRate.yaw = rate


def _velocity(sp: setpoint_t, payload: bytes, yaw_sign: float) -> None:
    vx, vy, vz, yawrate = _floats(payload, 4)
    sp.mode.x = sp.mode.y = sp.mode.z = modeVelocity
    sp.velocity.x, sp.velocity.y, sp.velocity.z = vx, vy, vz
    _yaw_rate(sp, yaw_sign * yawrate)


def _z_distance(sp: setpoint_t, payload: bytes, yaw_sign: float) -> None:
    roll, pitch, yawrate, z = _floats(payload, 4)
    sp.mode.z = modeAbs
    sp.position.z = z
    _yaw_rate(sp, yaw_sign * yawrate)
    _roll_pitch_abs(sp, roll, pitch)


def _hover(sp: setpoint_t, payload: bytes, yaw_sign: float) -> None:
    vx, vy, yawrate, z = _floats(payload, 4)
    sp.mode.z = modeAbs
    sp.position.z = z
    _yaw_rate(sp, yaw_sign * yawrate)
    sp.mode.x = sp.mode.y = modeVelocity
    sp.velocity.x, sp.velocity.y = vx, vy
    sp.velocity_body = True


def _alt_hold(sp: setpoint_t, payload: bytes) -> None:
    roll, pitch, yawrate, vz = _floats(payload, 4)
    sp.mode.z = modeVelocity
    sp.velocity.z = vz
    _yaw_rate(sp, yawrate)
    _roll_pitch_abs(sp, roll, pitch)


def _position(sp: setpoint_t, payload: bytes) -> None:
    x, y, z, yaw = _floats(payload, 4)
    sp.mode.x = sp.mode.y = sp.mode.z = modeAbs
    sp.position.x, sp.position.y, sp.position.z = x, y, z
    sp.mode.yaw = modeAbs
    sp.attitude.yaw = yaw


def _manual(sp: setpoint_t, payload: bytes) -> None:
    roll, pitch, yawrate, thrust, rate = _floats(payload, 3, "HB")
    if rate:
        sp.mode.roll = sp.mode.pitch = modeVelocity
        sp.attitudeRate.roll, sp.attitudeRate.pitch = roll, pitch
    else:
        _roll_pitch_abs(sp, roll, pitch)
    _yaw_rate(sp, yawrate)
    sp.thrust = float(thrust)


def _cppm(sp: setpoint_t, payload: bytes) -> None:
    aux_count = field_u8(payload, 0) & 0x0F
    if aux_count > CPPM_MAX_AUX_CHANNELS or len(payload) != 9 + 2 * aux_count:
        raise MalformedPacket("CPPM payload of %d bytes for %d aux channels" % (len(payload), aux_count))
    roll, pitch, yaw, thrust, *aux = struct.unpack("<%dH" % (4 + aux_count), payload[1:])
    self_level = not (aux_count >= 1 and aux[0] < 1500)

    def unit(value, mid, span):
        return (value - mid) / span

    sp.mode.yaw = modeVelocity
    if self_level:
        _roll_pitch_abs(sp, -unit(roll, 1500, 500) * CPPM_ANGLE_MAX_DEG, -unit(pitch, 1500, 500) * CPPM_ANGLE_MAX_DEG)
    else:  # rate mode: the firmware's 720 deg/s full scale
        sp.mode.roll = sp.mode.pitch = modeVelocity
        sp.attitudeRate.roll = -unit(roll, 1500, 500) * 720.0
        sp.attitudeRate.pitch = -unit(pitch, 1500, 500) * 720.0
    sp.attitudeRate.yaw = -unit(yaw, 1500, 500) * CPPM_YAW_RATE_MAX_DPS
    sp.thrust = max(0.0, unit(thrust, 1000, 1000) * UINT16_MAX)


_GENERIC_DECODERS: dict[int, Callable[[setpoint_t, bytes], None]] = {
    0: lambda sp, payload: None,  # stop: the null setpoint
    1: lambda sp, payload: _velocity(sp, payload, -1.0),
    2: lambda sp, payload: _z_distance(sp, payload, -1.0),
    3: _cppm,
    4: _alt_hold,
    5: lambda sp, payload: _hover(sp, payload, -1.0),
    7: _position,
    8: lambda sp, payload: _velocity(sp, payload, 1.0),
    9: lambda sp, payload: _z_distance(sp, payload, 1.0),
    10: lambda sp, payload: _hover(sp, payload, 1.0),
    11: _manual,
}


class CommanderService:
    """``cf``: the emulated Crazyflie (``commander_set_setpoint``, ``commander_get_active_priority``,
    ``commander_relax_priority``)."""

    def __init__(self, cf):
        self.cf = cf
        self.accepted = 0  # setpoints the commander took
        self.refused = 0  # setpoints a higher priority (the app) kept out
        self._thrust_locked = True  # crtp_commander_rpyt.c: no thrust before a zero-thrust packet

    def handle(self, packet: CrtpPacket, now: int) -> list:
        if packet.port == CRTP_PORT_SETPOINT:
            if packet.channel == SET_SETPOINT_CHANNEL:
                self._submit(self._decode_rpyt(packet.data))
            return []
        if packet.channel == SET_SETPOINT_CHANNEL:
            kind = field_u8(packet.data, 0)
            if kind == FULL_STATE_TYPE:
                raise Unserved("full-state setpoint")
            sp = setpoint_t()
            decoder = _GENERIC_DECODERS.get(kind)
            if decoder is not None:
                decoder(sp, packet.data[1:])
            self._submit(sp)
        elif packet.channel == META_COMMAND_CHANNEL:
            if field_u8(packet.data, 0) == META_NOTIFY_SETPOINTS_STOP:
                if len(packet.data) != 5:
                    raise MalformedPacket("notifySetpointsStop takes a u32")
                self.cf.commander_relax_priority()
        return []

    def _submit(self, sp: setpoint_t) -> None:
        if self.cf.commander_set_setpoint(sp, COMMANDER_PRIORITY_CRTP):
            self.accepted += 1
        else:
            self.refused += 1

    def _decode_rpyt(self, payload: bytes) -> setpoint_t:
        roll, pitch, yaw, thrust = _floats(payload, 3, "H")
        if self.cf.commander_get_active_priority() == COMMANDER_PRIORITY_DISABLE:
            self._thrust_locked = True
        if thrust == 0:
            self._thrust_locked = False
        sp = setpoint_t()
        sp.thrust = 0.0 if self._thrust_locked or thrust < MIN_THRUST else float(min(thrust, MAX_THRUST))
        sp.mode.z = sp.mode.x = sp.mode.y = modeDisable
        _roll_pitch_abs(sp, roll, pitch)
        _yaw_rate(sp, -yaw)
        return sp
