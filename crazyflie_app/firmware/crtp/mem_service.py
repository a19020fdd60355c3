"""crtp_mem.c (port 4): the memory subsystem, as far as a client of this emulation can tell.

cflib asks for the memories on every connect (and would wait forever without an answer). Served: the
high-level commander's trajectory memory (``TRAJ``, 4096 bytes, on the firmware plant: the firmware's own
handler, crtpCommanderHighLevelRead/WriteTrajectory, so cflib's ``TrajectoryMemory.write_data`` uploads
there and a write past its end is the firmware's EIO), then the Loco Positioning deck's (``LOCO2``, present
when ``deck.bcLoco`` reads 1): the emulation has no UWB anchors, so it reads as zeros, a deck that sees no
anchor (cfclient's Loco Positioning tab polls it).

    ch 0  [1]          -> [1, count]
          [2, id]      -> [2, id, type, size u32, 8-byte serial (zeros)]   (an unknown id: type 0, size 0)
    ch 1  read  [id, addr u32, len]   -> [id, addr u32, 0, len bytes]      (EIO outside the memory)
    ch 2  write [id, addr u32, data]  -> [id, addr u32, 0]                 (EIO outside it, or read-only)
"""
import errno
import struct

from crazyflie_app.firmware.crtp.packet import CRTP_MAX_DATA_SIZE, CrtpPacket, MalformedPacket, field_u8, reply

MEM_SETTINGS_CH, MEM_READ_CH, MEM_WRITE_CH = 0, 1, 2
MEM_CMD_GET_NBR, MEM_CMD_GET_INFO = 1, 2
MEM_TYPE_TRAJ, MEM_TYPE_LOCO2 = 0x12, 0x13
LOCO2_SIZE = 0x2000 + 256 * 0x100  # the id lists, then one page per possible anchor (cflib's LocoMemory2)
_ADDRESSED = 5  # id, addr u32
_READ_HEADER = 6  # id, addr u32, status


class MemService:
    """``registry``: the Crazyflie's LOG/PARAM registry (``deck.bcLoco`` says whether the Loco memory is there);
    ``high_level``: its high-level commander (the trajectory memory), or None."""

    def __init__(self, registry, high_level=None):
        self.registry = registry
        self.high_level = high_level

    def _memories(self) -> list[tuple[int, int]]:
        """(type, size) of each memory, by id."""
        try:
            loco = int(self.registry.param_read("deck.bcLoco"))
        except KeyError:  # a firmware image without the deck group
            loco = 0
        memories = [(MEM_TYPE_TRAJ, self.high_level.memory_size)] if self.high_level is not None else []
        return memories + ([(MEM_TYPE_LOCO2, LOCO2_SIZE)] if loco else [])

    def handle(self, packet: CrtpPacket, now: int) -> list[CrtpPacket]:
        memories = self._memories()
        if packet.channel == MEM_SETTINGS_CH:
            command = field_u8(packet.data, 0)
            if command == MEM_CMD_GET_NBR:
                return [reply(packet, bytes((MEM_CMD_GET_NBR, len(memories))))]
            if command == MEM_CMD_GET_INFO:
                mem_id = field_u8(packet.data, 1)
                kind, size = memories[mem_id] if mem_id < len(memories) else (0, 0)
                return [reply(packet, struct.pack("<BBBI", MEM_CMD_GET_INFO, mem_id, kind, size) + bytes(8))]
            return []
        if packet.channel not in (MEM_READ_CH, MEM_WRITE_CH):
            return []
        if len(packet.data) < _ADDRESSED + (packet.channel == MEM_READ_CH):
            raise MalformedPacket("memory access without id, address (and length)")
        mem_id, address = packet.data[0], struct.unpack("<I", packet.data[1:5])[0]
        kind = memories[mem_id][0] if mem_id < len(memories) else None
        if packet.channel == MEM_WRITE_CH:
            written = kind == MEM_TYPE_TRAJ and self.high_level.memory_write(address, packet.data[_ADDRESSED:])
            return [reply(packet, packet.data[:_ADDRESSED] + bytes((0 if written else errno.EIO,)))]
        length = packet.data[5]
        inside = kind is not None and address + length <= memories[mem_id][1]
        if not inside or length > CRTP_MAX_DATA_SIZE - _READ_HEADER:
            return [reply(packet, packet.data[:_ADDRESSED] + bytes((errno.EIO,)))]
        data = self.high_level.memory_read(address, length) if kind == MEM_TYPE_TRAJ else bytes(length)
        return [reply(packet, packet.data[:_ADDRESSED] + b"\0" + data)]
