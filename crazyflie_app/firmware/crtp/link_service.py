"""crtpservice.c (port 15): the link-layer services a client uses to find and probe a Crazyflie.

    ch 0  echo    the packet comes back unchanged (cflib's link statistics ping it every 100 ms)
    ch 1  source  a 30-byte packet starting "Bitcraze Crazyflie" (cflib's first request on connect: the
                  magic string says the protocol version can be asked for)
    ch 2  sink    swallowed
    ch 3  null    answered with a null packet: the radio's downlink poll, and the probe of cflib's UDP scan
"""
from crazyflie_app.firmware.crtp.packet import CRTP_MAX_DATA_SIZE, CrtpPacket, reply

LINK_ECHO, LINK_SOURCE, LINK_SINK, LINK_NULL = 0, 1, 2, 3
SOURCE_MAGIC = b"Bitcraze Crazyflie"


def handle(packet: CrtpPacket, now: int) -> list[CrtpPacket]:
    if packet.channel == LINK_ECHO:
        return [reply(packet, packet.data)]
    if packet.channel == LINK_SOURCE:
        return [reply(packet, SOURCE_MAGIC.ljust(CRTP_MAX_DATA_SIZE, b"\0"))]
    if packet.channel == LINK_NULL:
        return [reply(packet, b"")]
    return []


def is_keepalive(packet: CrtpPacket) -> bool:
    """A null packet or an echo: a client saying it is there, not asking the firmware for anything."""
    return packet.port == 0x0F and packet.channel in (LINK_ECHO, LINK_NULL)
