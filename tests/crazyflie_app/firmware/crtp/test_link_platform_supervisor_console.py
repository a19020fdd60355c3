"""The small ports: link services, platform queries, memories, supervisor state and arming, console lines."""
import errno
import struct

import pytest

from crazyflie_app.firmware import Crazyflie
from crazyflie_app.firmware.crtp import link_service
from crazyflie_app.firmware.crtp.mem_service import MEM_TYPE_LOCO2, MemService
from crazyflie_app.firmware.crtp.console_service import ConsoleService
from crazyflie_app.firmware.crtp.packet import (CRTP_PORT_LINK, CRTP_PORT_MEM, CRTP_PORT_PLATFORM,
                                                CRTP_PORT_SUPERVISOR, CrtpPacket, Unserved)
from crazyflie_app.firmware.crtp.platform_service import CRTP_PROTOCOL_VERSION, PlatformService
from crazyflie_app.firmware.crtp.supervisor_service import SupervisorService


def test_that_the_link_port_echoes_sources_and_answers_null_packets():
    (echo,) = link_service.handle(CrtpPacket(CRTP_PORT_LINK, 0, b"ping"), 0)
    (source,) = link_service.handle(CrtpPacket(CRTP_PORT_LINK, 1, b"\0"), 0)
    (null,) = link_service.handle(CrtpPacket(CRTP_PORT_LINK, 3), 0)
    assert echo.data == b"ping" and source.data.startswith(b"Bitcraze Crazyflie") and len(source.data) == 30
    assert null.is_null() and null.data == b""
    assert link_service.handle(CrtpPacket(CRTP_PORT_LINK, 2, b"x"), 0) == []


def test_that_the_platform_port_tells_version_and_device():
    service = PlatformService(Crazyflie())
    (protocol,) = service.handle(CrtpPacket(CRTP_PORT_PLATFORM, 1, b"\0"), 0)
    (device,) = service.handle(CrtpPacket(CRTP_PORT_PLATFORM, 1, b"\x02"), 0)
    assert struct.unpack("<Bi", protocol.data) == (0, CRTP_PROTOCOL_VERSION)
    assert device.data == b"\x02Crazyflie Bolt 1.1"


def test_that_the_loco_deck_memory_reads_as_no_anchors_and_nothing_else_is_there():
    with_loco, without = MemService(Crazyflie().registry), MemService(Crazyflie(decks=("bcFlow2",)).registry)
    (count,) = with_loco.handle(CrtpPacket(CRTP_PORT_MEM, 0, b"\x01"), 0)
    (info,) = with_loco.handle(CrtpPacket(CRTP_PORT_MEM, 0, b"\x02\x00"), 0)
    (read,) = with_loco.handle(CrtpPacket(CRTP_PORT_MEM, 1, bytes([0, 0, 0x10, 0, 0, 9])), 0)  # active ids
    (write,) = with_loco.handle(CrtpPacket(CRTP_PORT_MEM, 2, bytes([0, 0, 0, 0, 0, 7])), 0)
    assert count.data == b"\x01\x01" and info.data[2] == MEM_TYPE_LOCO2
    assert read.data == bytes([0, 0, 0x10, 0, 0, 0]) + bytes(9)  # status 0, no anchor
    assert write.data == bytes([0, 0, 0, 0, 0, errno.EIO])
    (none,) = without.handle(CrtpPacket(CRTP_PORT_MEM, 0, b"\x01"), 0)
    (outside,) = without.handle(CrtpPacket(CRTP_PORT_MEM, 1, bytes([0, 0, 0, 0, 0, 4])), 0)
    assert none.data == b"\x01\x00" and outside.data == bytes([0, 0, 0, 0, 0, errno.EIO])


def test_that_the_supervisor_port_reports_state_and_arms():
    cf = Crazyflie()
    service = SupervisorService(cf)
    (bits,) = service.handle(CrtpPacket(CRTP_PORT_SUPERVISOR, 0, b"\x0c"), 0)
    assert bits.data == b"\x8c\x01\x00"  # can be armed, nothing else
    (armed,) = service.handle(CrtpPacket(CRTP_PORT_SUPERVISOR, 1, b"\x01\x01"), 0)
    assert armed.data == b"\x81\x01\x01" and cf.supervisor_is_armed()
    (is_armed,) = service.handle(CrtpPacket(CRTP_PORT_SUPERVISOR, 0, b"\x02"), 0)
    assert is_armed.data == b"\x82\x01"
    with pytest.raises(Unserved):
        service.handle(CrtpPacket(CRTP_PORT_SUPERVISOR, 1, b"\x03"), 0)  # emergency stop


def test_that_the_deprecated_platform_arming_warns_on_the_console():
    cf = Crazyflie()
    (answer,) = PlatformService(cf).handle(CrtpPacket(CRTP_PORT_PLATFORM, 0, b"\x01\x01"), 0)
    assert answer.data == b"\x01\x01\x01" and cf.supervisor_is_armed()
    assert "deprecated" in cf.console.lines[-1][2]


def test_that_console_lines_are_cut_into_packets_and_the_backlog_is_bounded():
    cf = Crazyflie()
    console = ConsoleService(cf.console, backlog_packets=4)
    cf.debug_print("FORANAV", "x" * 40 + " caf\u00e9")
    assert b"".join(p.data for p in console.pending) == b"FORANAV: " + b"x" * 40 + b" caf?\n"
    assert all(len(p.data) <= 30 for p in console.pending)
    for i in range(10):
        cf.debug_print("SUP", "line %d" % i)
    assert len(console.pending) == 4 and console.dropped > 0
    assert console.pending[-1].data == b"SUP: line 9\n"
    console.detach()
    cf.debug_print("SUP", "after")
    assert console.pending[-1].data == b"SUP: line 9\n"
