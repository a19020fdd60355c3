"""The datagram form of a packet, and the C conversions values take on their way to a client."""
import math
import struct

import pytest

from crazyflie_app.firmware.crtp.packet import (CRTP_MAX_DATA_SIZE, CRTP_PORT_LINK, CRTP_PORT_LOG, CrtpPacket,
                                                MalformedPacket, decode, field_u16)
from crazyflie_app.firmware.crtp.values import (LOG_FP16, LOG_TYPE_CODES, pack_log_value, pack_param_value,
                                                param_size, unpack_param_value)


def test_that_a_packet_round_trips_through_its_datagram():
    for port in range(16):
        for channel in range(4):
            for data in (b"", b"\x01", bytes(range(CRTP_MAX_DATA_SIZE))):
                packet = CrtpPacket(port, channel, data)
                assert decode(packet.encode()) == packet


def test_that_the_legacy_link_bits_are_ignored_and_the_null_packet_is_recognised():
    assert decode(bytes([0x5C | 2, 7])) == CrtpPacket(CRTP_PORT_LOG, 2, b"\x07")
    assert decode(b"\xff").is_null() and decode(b"\xf3").is_null()
    assert not decode(b"\xf0").is_null()
    assert CrtpPacket(CRTP_PORT_LINK, 3).encode() == b"\xf3"


def test_that_empty_and_oversized_datagrams_are_no_packet():
    assert decode(b"") is None
    assert decode(bytes(2 + CRTP_MAX_DATA_SIZE)) is None
    with pytest.raises(ValueError):
        CrtpPacket(16, 0)
    with pytest.raises(ValueError):
        CrtpPacket(0, 0, bytes(CRTP_MAX_DATA_SIZE + 1))


def test_that_a_truncated_field_is_malformed():
    assert field_u16(b"\x34\x12", 0) == 0x1234
    with pytest.raises(MalformedPacket):
        field_u16(b"\x34", 0)


def test_that_log_values_convert_as_c_does():
    as_float, as_u8, as_i16, as_u32 = (LOG_TYPE_CODES[t] for t in ("float", "uint8_t", "int16_t", "uint32_t"))
    assert struct.unpack("<f", pack_log_value(1.25, as_float))[0] == 1.25
    assert pack_log_value(300, as_u8) == bytes([300 & 0xFF])  # the low byte
    assert pack_log_value(-2.7, as_i16) == struct.pack("<h", -2)  # truncation towards zero
    assert pack_log_value(math.nan, as_u8) == b"\0"  # NaN -> 0 (the Cortex-M4's VCVT)
    assert pack_log_value(1e12, as_u32) == struct.pack("<I", 2 ** 31 - 1)  # saturated to int32 first
    assert struct.unpack("<f", pack_log_value(1e300, as_float))[0] == math.inf
    assert struct.unpack("<e", pack_log_value(-1e6, LOG_FP16))[0] == -math.inf
    assert struct.unpack("<e", pack_log_value(0.5, LOG_FP16))[0] == 0.5
    assert struct.unpack("<f", pack_log_value(7, as_float))[0] == 7.0  # an integer fetched as float


def test_that_param_values_round_trip_in_their_own_size():
    for c_type, value in (("uint8_t", 200), ("int8_t", -5), ("uint16_t", 65535), ("int16_t", -300),
                          ("uint32_t", 2 ** 32 - 1), ("int32_t", -2 ** 31), ("float", 0.5)):
        raw = pack_param_value(value, c_type)
        assert len(raw) == param_size(c_type)
        assert unpack_param_value(raw, c_type) == value
