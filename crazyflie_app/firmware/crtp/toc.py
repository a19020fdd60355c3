"""The table of contents that the log and param ports share (log.c / param_logic.c, TOC protocol v2).

A TOC is the registry's variables in id order, each with its type byte; its CRC is a hash of every entry
chained in order (crc32 over the previous CRC, the type byte and 'group.name'), so a client's TOC cache
(cflib's ``TocCache``, keyed by the CRC) is reused exactly while the tables are the same. On the wire:

    info request  [CMD_GET_INFO_V2]            -> [CMD_GET_INFO_V2, count u16, crc u32, <port extras>]
    item request  [CMD_GET_ITEM_V2, id u16]    -> [CMD_GET_ITEM_V2, id u16, type, group 0, name 0]
                                                  (an id past the end: [CMD_GET_ITEM_V2] alone)

The version-1 commands (one-byte ids) are not served, as in the firmware this follows.
"""
import struct
import zlib
from collections.abc import Sequence
from dataclasses import dataclass

from crazyflie_app.firmware.crtp.packet import CRTP_MAX_DATA_SIZE, CrtpPacket, field_u16, reply

TOC_CH = 0
CMD_GET_ITEM_V2 = 2
CMD_GET_INFO_V2 = 3
_ITEM_HEADER = 4  # cmd, id u16, type


@dataclass(frozen=True)
class TocEntry:
    group: str
    name: str
    type_byte: int


@dataclass(frozen=True)
class Toc:
    entries: tuple
    crc: int

    def info_reply(self, request: CrtpPacket, extras: bytes = b"") -> CrtpPacket:
        return reply(request, struct.pack("<BHI", CMD_GET_INFO_V2, len(self.entries), self.crc) + extras)

    def item_reply(self, request: CrtpPacket) -> CrtpPacket:
        index = field_u16(request.data, 1)
        if index >= len(self.entries):
            return reply(request, bytes((CMD_GET_ITEM_V2,)))
        entry = self.entries[index]
        names = entry.group.encode("ascii") + b"\0" + entry.name.encode("ascii") + b"\0"
        return reply(request, struct.pack("<BHB", CMD_GET_ITEM_V2, index, entry.type_byte) + names)


def build_toc(entries: Sequence[TocEntry]) -> Toc:
    """The TOC of ``entries`` (in id order); a name too long for an item packet is a table error, as the
    firmware's ASSERT at logInit/paramInit."""
    crc = 0
    for entry in entries:
        if _ITEM_HEADER + len(entry.group) + len(entry.name) + 2 > CRTP_MAX_DATA_SIZE:
            raise ValueError("TOC entry %s.%s: name too long for a CRTP packet" % (entry.group, entry.name))
        crc = zlib.crc32(struct.pack("<IB", crc, entry.type_byte) + ("%s.%s" % (entry.group, entry.name)).encode(
            "ascii"))
    return Toc(tuple(entries), crc)


def split_group_and_name(full_name: str) -> tuple[str, str]:
    group, _, name = full_name.partition(".")
    return group, name
