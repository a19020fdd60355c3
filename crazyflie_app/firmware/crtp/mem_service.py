"""crtp_mem.c (port 4): the memory subsystem, which this emulation has none of.

cflib asks for the number of memories on every connect (and would wait forever without an answer), so the
port answers: ``[1] -> [1, 0]`` (no memories, the deck EEPROMs and LED rings included); a read
``[id, addr u32, len]`` or a write ``[id, addr u32, data]`` -> ``[id, addr u32, EIO]``; an info request
``[2, id]`` -> an empty description (type 0, size 0, an 8-byte zero serial, as the firmware pads it).
"""
import errno
import struct

from crazyflie_app.firmware.crtp.packet import CrtpPacket, MalformedPacket, field_u8, reply

MEM_SETTINGS_CH, MEM_READ_CH, MEM_WRITE_CH = 0, 1, 2
MEM_CMD_GET_NBR, MEM_CMD_GET_INFO = 1, 2
MEMORY_COUNT = 0
_ADDRESSED = 5  # id, addr u32


def handle(packet: CrtpPacket, now: int) -> list[CrtpPacket]:
    if packet.channel == MEM_SETTINGS_CH:
        command = field_u8(packet.data, 0)
        if command == MEM_CMD_GET_NBR:
            return [reply(packet, bytes((MEM_CMD_GET_NBR, MEMORY_COUNT)))]
        if command == MEM_CMD_GET_INFO:
            return [reply(packet, bytes((MEM_CMD_GET_INFO, field_u8(packet.data, 1), 0)) + struct.pack("<I", 0)
                          + bytes(8))]
        return []
    if packet.channel in (MEM_READ_CH, MEM_WRITE_CH):
        if len(packet.data) < _ADDRESSED + (packet.channel == MEM_READ_CH):
            raise MalformedPacket("memory access without id, address (and length)")
        return [reply(packet, packet.data[:_ADDRESSED] + bytes((errno.EIO,)))]
    return []
