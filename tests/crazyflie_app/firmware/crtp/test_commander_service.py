"""A client's setpoints: decoded as the firmware does, handed to the commander at COMMANDER_PRIORITY_CRTP."""
import struct

import pytest

from crazyflie_app.firmware import Crazyflie
from crazyflie_app.firmware.commander import (COMMANDER_PRIORITY_CRTP, COMMANDER_PRIORITY_EXTRX, modeAbs,
                                              modeDisable, modeVelocity, setpoint_t)
from crazyflie_app.firmware.crtp.commander_service import CommanderService
from crazyflie_app.firmware.crtp.packet import (CRTP_PORT_SETPOINT, CRTP_PORT_SETPOINT_GENERIC, CrtpPacket,
                                                MalformedPacket, Unserved)


def _send(service, port, channel, data):
    return service.handle(CrtpPacket(port, channel, data), 0)


def _held(cf):
    return cf.commander.commander_get_setpoint()


def test_that_generic_setpoints_decode_into_the_commanders_setpoint():
    cf = Crazyflie()
    service = CommanderService(cf)
    _send(service, CRTP_PORT_SETPOINT_GENERIC, 0, bytes([10]) + struct.pack("<4f", 0.2, -0.1, 15.0, 1.1))  # hover
    sp = _held(cf)
    assert (sp.mode.x, sp.mode.y, sp.mode.z, sp.mode.yaw) == (modeVelocity, modeVelocity, modeAbs, modeVelocity)
    assert (sp.velocity.x, sp.velocity.y, sp.position.z, sp.attitudeRate.yaw, sp.velocity_body) == pytest.approx(
        (0.2, -0.1, 1.1, 15.0, True))
    assert cf.commander.commander_get_active_priority() == COMMANDER_PRIORITY_CRTP
    _send(service, CRTP_PORT_SETPOINT_GENERIC, 0, bytes([7]) + struct.pack("<4f", 1.0, 2.0, 0.5, 90.0))  # position
    sp = _held(cf)
    assert (sp.position.x, sp.position.y, sp.position.z, sp.attitude.yaw) == (1.0, 2.0, 0.5, 90.0)
    assert sp.mode.yaw == modeAbs and not sp.velocity_body
    _send(service, CRTP_PORT_SETPOINT_GENERIC, 0, bytes([1]) + struct.pack("<4f", 0, 0, 0, 10.0))  # legacy
    assert _held(cf).attitudeRate.yaw == -10.0
    _send(service, CRTP_PORT_SETPOINT_GENERIC, 0, bytes([0]))  # stop
    assert _held(cf).is_null()
    _send(service, CRTP_PORT_SETPOINT_GENERIC, 0, bytes([99, 1, 2]))  # unknown type: the null setpoint
    assert _held(cf).is_null() and service.accepted == 5


def test_that_wrong_sizes_are_malformed_and_full_state_is_not_served():
    service = CommanderService(Crazyflie())
    with pytest.raises(MalformedPacket):
        _send(service, CRTP_PORT_SETPOINT_GENERIC, 0, bytes([10]) + b"\0" * 15)
    with pytest.raises(MalformedPacket):
        _send(service, CRTP_PORT_SETPOINT_GENERIC, 0, b"")
    with pytest.raises(Unserved):
        _send(service, CRTP_PORT_SETPOINT_GENERIC, 0, bytes([6]) + b"\0" * 28)
    assert service.accepted == 0


def test_that_the_app_at_a_higher_priority_keeps_the_client_out():
    cf = Crazyflie()
    service = CommanderService(cf)
    cf.commander_set_setpoint(setpoint_t(), COMMANDER_PRIORITY_EXTRX)
    _send(service, CRTP_PORT_SETPOINT_GENERIC, 0, bytes([8]) + struct.pack("<4f", 1, 1, 1, 1))
    assert (service.accepted, service.refused) == (0, 1)
    _send(service, CRTP_PORT_SETPOINT_GENERIC, 1, bytes([0]) + struct.pack("<I", 0))  # notifySetpointsStop
    _send(service, CRTP_PORT_SETPOINT_GENERIC, 0, bytes([8]) + struct.pack("<4f", 1, 1, 1, 1))
    assert service.accepted == 1, "after the relax the client's setpoint is taken"


def test_that_legacy_thrust_stays_locked_until_a_zero_thrust():
    cf = Crazyflie()
    service = CommanderService(cf)
    _send(service, CRTP_PORT_SETPOINT, 0, struct.pack("<3fH", 5.0, -3.0, 20.0, 40000))
    sp = _held(cf)
    assert sp.thrust == 0.0 and (sp.attitude.roll, sp.attitude.pitch, sp.attitudeRate.yaw) == (5.0, -3.0, -20.0)
    assert (sp.mode.roll, sp.mode.z) == (modeAbs, modeDisable)
    _send(service, CRTP_PORT_SETPOINT, 0, struct.pack("<3fH", 0, 0, 0, 0))
    _send(service, CRTP_PORT_SETPOINT, 0, struct.pack("<3fH", 0, 0, 0, 65000))
    assert _held(cf).thrust == 60000.0  # unlocked, and capped at MAX_THRUST
