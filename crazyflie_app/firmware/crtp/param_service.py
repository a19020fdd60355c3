"""param_logic.c over CRTP (port 2): the param TOC of the registry, reads, writes and the misc commands.

    ch 0  TOC (toc.py); the type byte is param.h's code, with PARAM_RONLY (0x40) for read-only params
    ch 1  read   [id u16]          -> [id u16, 0, value]          unknown id: [id u16, ENOENT]
    ch 2  write  [id u16, value]   -> [id u16, value now]         unknown id: [id u16, PARAM_NOT_FOUND]
    ch 3  misc   [command, ...]:
          SETBYNAME          [0, group 0 name 0 type value] -> [0, group 0 name 0 status]
                             (ENOENT unknown, EINVAL wrong type or size, EACCES read-only, ERANGE outside
                             the param's valid range)
          GET_EXTENDED_TYPE  (v1 2, v2 7): no param of this emulation is extended (persistent), so
                             [2, id, PARAM_NOT_FOUND] and [7, id, ENOENT]
          PERSISTENT_STORE / _CLEAR (3 / 5): refused, [cmd, id, ENOENT]: there is no storage to keep them in
          PERSISTENT_GET_STATE (4): [4, id, NOT_STORED, default value]
          GET_DEFAULT_VALUE  (v1 6, v2 8): the value the param had when its table was registered;
                             read-only params have none (PARAM_NOT_FOUND / ENOENT), as in the firmware

A write goes through the registry's paramSet*, like any firmware write, and is echoed with the value the
param holds afterwards: a write outside an app param's valid range (PARAM table), or NaN, is refused there and
the echo carries the value the param kept. Two refusals the firmware does not make, so that a client never waits forever:
a write to a read-only param, or one whose value has the wrong size, is answered with the unchanged value.
"""
import errno

from crazyflie_app.firmware.crtp.packet import CrtpPacket, MalformedPacket, field_u8, field_u16, reply
from crazyflie_app.firmware.crtp.toc import (CMD_GET_INFO_V2, CMD_GET_ITEM_V2, TOC_CH, Toc, TocEntry, build_toc,
                                             split_group_and_name)
from crazyflie_app.firmware.crtp.values import (PARAM_RONLY, PARAM_TYPE_CODES, pack_param_value, param_size,
                                                unpack_param_value)
from crazyflie_app.firmware.logparam import PARAM_FLOAT, LogParamRegistry, ParamRangeError

READ_CH, WRITE_CH, MISC_CH = 1, 2, 3
MISC_SETBYNAME, MISC_VALUE_UPDATED, MISC_GET_EXTENDED_TYPE, MISC_PERSISTENT_STORE = 0, 1, 2, 3
MISC_PERSISTENT_GET_STATE, MISC_PERSISTENT_CLEAR, MISC_GET_DEFAULT_VALUE = 4, 5, 6
MISC_GET_EXTENDED_TYPE_V2, MISC_GET_DEFAULT_VALUE_V2 = 7, 8
PARAM_PERSISTENT_NOT_STORED = 0
PARAM_NOT_FOUND = 2


class ParamService:
    """The param port of one Crazyflie, on its registry."""

    def __init__(self, registry: LogParamRegistry):
        self.registry = registry
        self.writes = 0  # values a client changed
        self.refused_writes = 0  # writes answered with the unchanged value
        self.toc_items_served = 0  # a client with the TOC in its cache asks for none
        self._toc = None
        self._params = []  # (group, name, Entry, ParamVarId) in id order

    # -- the TOC --------------------------------------------------------------------------------------------

    def _refresh(self) -> None:
        entries = self.registry.param_entries()
        if self._toc is not None and len(self._params) == len(entries):  # tables only ever grow
            return
        self._params = []
        toc_entries = []
        for full_name, entry in entries:
            group, name = split_group_and_name(full_name)
            self._params.append((group, name, entry, self.registry.param_get_var_id(group, name)))
            toc_entries.append(TocEntry(group, name, PARAM_TYPE_CODES[entry.type]
                                        | (PARAM_RONLY if entry.read_only else 0)))
        self._toc = build_toc(toc_entries)

    def toc(self) -> Toc:
        self._refresh()
        return self._toc

    # -- requests -------------------------------------------------------------------------------------------

    def handle(self, packet: CrtpPacket, now: int) -> list[CrtpPacket]:
        self._refresh()
        if packet.channel == TOC_CH:
            command = field_u8(packet.data, 0)
            if command == CMD_GET_INFO_V2:
                return [self._toc.info_reply(packet)]
            if command == CMD_GET_ITEM_V2:
                self.toc_items_served += 1
                return [self._toc.item_reply(packet)]
            return []
        if packet.channel == READ_CH:
            return [self._read(packet)]
        if packet.channel == WRITE_CH:
            return [self._write(packet)]
        return self._misc(packet)

    def _param(self, index: int):
        return self._params[index] if index < len(self._params) else None

    def _value_bytes(self, index: int) -> bytes:
        group, name, entry, var_id = self._params[index]
        try:
            value = self.registry.param_read("%s.%s" % (group, name))
        except (ValueError, OverflowError):  # an owner attribute that is not a number: its bits are unknown
            value = 0
        return pack_param_value(value, entry.type)

    def _read(self, packet: CrtpPacket) -> CrtpPacket:
        index = field_u16(packet.data, 0)
        if self._param(index) is None:
            return reply(packet, packet.data[:2] + bytes((errno.ENOENT,)))
        return reply(packet, packet.data[:2] + b"\0" + self._value_bytes(index))

    def _write(self, packet: CrtpPacket) -> CrtpPacket:
        index = field_u16(packet.data, 0)
        param = self._param(index)
        if param is None:
            return reply(packet, packet.data[:2] + bytes((PARAM_NOT_FOUND,)))
        _, _, entry, var_id = param
        raw = packet.data[2:]
        if entry.read_only or len(raw) != param_size(entry.type):
            self.refused_writes += 1
        else:
            try:
                self._set(entry, var_id, unpack_param_value(raw, entry.type))
            except ParamRangeError:  # outside the param's valid range: the echo carries the value it kept
                self.refused_writes += 1
        return reply(packet, packet.data[:2] + self._value_bytes(index))

    def _set(self, entry, var_id, value: float | int) -> None:
        if entry.type == PARAM_FLOAT:
            self.registry.param_set_float(var_id, value)
        else:
            self.registry.param_set_int(var_id, value)
        self.writes += 1

    # -- misc -----------------------------------------------------------------------------------------------

    def _misc(self, packet: CrtpPacket) -> list[CrtpPacket]:
        command = field_u8(packet.data, 0)
        if command == MISC_SETBYNAME:
            return [self._set_by_name(packet)]
        if command in (MISC_VALUE_UPDATED,) or command > MISC_GET_DEFAULT_VALUE_V2:
            return []  # a firmware-to-client message, or nothing the firmware knows
        index = field_u16(packet.data, 1)
        head = packet.data[:3]
        param = self._param(index)
        if command == MISC_GET_EXTENDED_TYPE:
            return [reply(packet, head + bytes((PARAM_NOT_FOUND,)))]
        if command in (MISC_GET_EXTENDED_TYPE_V2, MISC_PERSISTENT_STORE, MISC_PERSISTENT_CLEAR):
            return [reply(packet, head + bytes((errno.ENOENT,)))]
        if command == MISC_PERSISTENT_GET_STATE:
            if param is None:
                return [reply(packet, head + bytes((PARAM_NOT_FOUND,)))]
            return [reply(packet, head + bytes((PARAM_PERSISTENT_NOT_STORED,)) + self._default_bytes(param))]
        # GET_DEFAULT_VALUE, v1 and v2
        v2 = command == MISC_GET_DEFAULT_VALUE_V2
        if param is None or param[2].read_only:
            return [reply(packet, head + bytes((errno.ENOENT if v2 else PARAM_NOT_FOUND,)))]
        return [reply(packet, head + (b"\0" if v2 else b"") + self._default_bytes(param))]

    def _default_bytes(self, param) -> bytes:
        _, _, entry, var_id = param
        return pack_param_value(self.registry.param_get_default(var_id), entry.type)

    def _set_by_name(self, packet: CrtpPacket) -> CrtpPacket:
        fields = packet.data[1:].split(b"\0", 2)
        if len(fields) < 3:
            raise MalformedPacket("setbyname: group and name must end with a 0 byte")
        group_raw, name_raw, rest = fields
        names_end = 1 + len(group_raw) + 1 + len(name_raw) + 1
        status = self._set_by_name_status(group_raw.decode("latin-1"), name_raw.decode("latin-1"), rest)
        return reply(packet, packet.data[:names_end] + bytes((status,)))

    def _set_by_name_status(self, group: str, name: str, rest: bytes) -> int:
        index = next((i for i, p in enumerate(self._params) if p[0] == group and p[1] == name), None)
        if index is None:
            return errno.ENOENT
        _, _, entry, var_id = self._params[index]
        if not rest or rest[0] != PARAM_TYPE_CODES[entry.type] or len(rest) - 1 != param_size(entry.type):
            return errno.EINVAL
        if entry.read_only:
            return errno.EACCES
        try:
            self._set(entry, var_id, unpack_param_value(rest[1:], entry.type))
        except ParamRangeError:
            self.refused_writes += 1
            return errno.ERANGE
        return 0
