"""crtp.h: one CRTP packet, and its form on the wire (cflib's UDP link: one packet per datagram).

A datagram is the header byte followed by 0..30 data bytes. The header holds the port (high nibble) and the
channel (low two bits); bits 2-3 are a legacy link field that cflib sets and the firmware ignores. A packet
on port 15 channel 3 is the *null packet*, which the radio uses to poll for downlink data and cflib's UDP
scan uses as a probe (``CRTP_IS_NULL_PACKET``: ``(header & 0xF3) == 0xF3``).

``decode`` returns None for what no firmware could receive (an empty or oversized datagram); everything else
decodes, and the services decide what a payload means: one they cannot parse raises ``MalformedPacket``, one
the firmware serves and this emulation does not raises ``Unserved`` (the server drops and counts both).
"""
from dataclasses import dataclass

CRTP_MAX_DATA_SIZE = 30
NULL_HEADER = 0xFF  # port 15, channel 3: what a null packet looks like on the wire

# CRTPPort
CRTP_PORT_CONSOLE = 0x00
CRTP_PORT_PARAM = 0x02
CRTP_PORT_SETPOINT = 0x03
CRTP_PORT_MEM = 0x04
CRTP_PORT_LOG = 0x05
CRTP_PORT_LOCALIZATION = 0x06
CRTP_PORT_SETPOINT_GENERIC = 0x07
CRTP_PORT_SETPOINT_HL = 0x08
CRTP_PORT_SUPERVISOR = 0x09
CRTP_PORT_PLATFORM = 0x0D
CRTP_PORT_LINK = 0x0F


@dataclass(frozen=True)
class CrtpPacket:
    """CRTPPacket: port (0..15), channel (0..3) and up to CRTP_MAX_DATA_SIZE bytes of data."""
    port: int
    channel: int
    data: bytes = b""

    def __post_init__(self):
        if not (0 <= self.port <= 15 and 0 <= self.channel <= 3 and len(self.data) <= CRTP_MAX_DATA_SIZE):
            raise ValueError("CRTP packet out of range: port %r channel %r, %d data bytes"
                             % (self.port, self.channel, len(self.data)))

    @property
    def header(self) -> int:
        """CRTP_HEADER(port, channel), as the firmware builds it (legacy link bits clear)."""
        return (self.port << 4) | self.channel

    def is_null(self) -> bool:
        return self.port == CRTP_PORT_LINK and self.channel == 3

    def encode(self) -> bytes:
        return bytes((self.header,)) + self.data


def decode(datagram: bytes) -> CrtpPacket | None:
    """The packet of one datagram, or None when it cannot be one (empty, or longer than a CRTP packet)."""
    if not 1 <= len(datagram) <= 1 + CRTP_MAX_DATA_SIZE:
        return None
    header = datagram[0]
    return CrtpPacket(header >> 4, header & 0x03, bytes(datagram[1:]))


def reply(request: CrtpPacket, data: bytes) -> CrtpPacket:
    """A packet back on the request's port and channel (how every firmware service answers)."""
    return CrtpPacket(request.port, request.channel, bytes(data[:CRTP_MAX_DATA_SIZE]))


class MalformedPacket(ValueError):
    """A request no firmware service could parse (too short, fields out of range)."""


class Unserved(Exception):
    """A request the firmware serves but this emulation does not (e.g. an emergency stop)."""


def field_u8(data: bytes, offset: int) -> int:
    """The byte at ``offset`` of a payload (MalformedPacket when the payload is shorter)."""
    if len(data) < offset + 1:
        raise MalformedPacket("truncated: no byte at %d" % offset)
    return data[offset]


def field_u16(data: bytes, offset: int) -> int:
    """The little-endian u16 at ``offset`` of a payload (MalformedPacket when the payload is shorter)."""
    if len(data) < offset + 2:
        raise MalformedPacket("truncated: no u16 at %d" % offset)
    return data[offset] | data[offset + 1] << 8
