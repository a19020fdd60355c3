"""log.c over CRTP (port 5): the log TOC of the registry, log blocks, and their data at their periods.

Channel 0 serves the TOC (``toc.py``). Channel 1 takes the block commands and answers each with
``[command, block id, status]`` (0 or an errno):

    CREATE_BLOCK_V2  [6, id, (fetch type, var id u16) ...]   EEXIST, ENOMEM (16 blocks, 128 variables),
    APPEND_BLOCK_V2  [7, id, (fetch type, var id u16) ...]   ENOENT (no block / no variable), E2BIG (> 26 bytes)
    DELETE_BLOCK     [2, id]            START_BLOCK  [3, id, period in 10 ms]   (period 0: one sample now)
    STOP_BLOCK       [4, id]            START_BLOCK_V2 [8, id, period in ms u16]
    RESET            [5]                anything else: ENOEXEC (as the firmware, which dropped the v1 forms)

Channel 2 carries the data: ``[block id, timestamp u24 (ms), values ...]``, each variable fetched as the type
the client asked for (``values.pack_log_value``). A block samples at its period from its start tick (a
FreeRTOS auto-reload timer), reading the registry's live values then: the same numbers the firmware's log
task would copy.

Two choices of this emulation: a create or append that fails changes nothing (the firmware may keep a
half-built block), and a raw-memory variable (var id 0xFFFF) is refused with ENOENT (there is no memory
to read).
"""
import errno
from dataclasses import dataclass, field

from crazyflie_app.firmware.crtp.packet import CRTP_PORT_LOG, CrtpPacket, MalformedPacket, field_u8, field_u16, reply
from crazyflie_app.firmware.crtp.toc import (CMD_GET_INFO_V2, CMD_GET_ITEM_V2, TOC_CH, Toc, TocEntry, build_toc,
                                             split_group_and_name)
from crazyflie_app.firmware.crtp.values import LOG_TYPE_CODES, log_type_size, pack_log_value
from crazyflie_app.firmware.logparam import LOG_FLOAT, LogParamRegistry

CONTROL_CH, LOG_CH = 1, 2
CONTROL_DELETE_BLOCK, CONTROL_START_BLOCK, CONTROL_STOP_BLOCK, CONTROL_RESET = 2, 3, 4, 5
CONTROL_CREATE_BLOCK_V2, CONTROL_APPEND_BLOCK_V2, CONTROL_START_BLOCK_V2 = 6, 7, 8
LOG_MAX_BLOCKS = 16
LOG_MAX_OPS = 128
LOG_MAX_LEN = 26  # data bytes of one block: 30 minus the block id and the 24-bit timestamp
MEMORY_VARIABLE_ID = 0xFFFF
TIMESTAMP_MASK = 0xFFFFFF
_SETTING_SIZE = 3  # fetch type, var id u16


@dataclass(frozen=True)
class _Op:
    var_id: int
    storage: str  # the variable's C type
    fetch: int  # the log type code it is sent as


@dataclass
class LogBlock:
    id: int
    ops: list = field(default_factory=list)
    period_ms: int = 0
    next_due: int | None = None  # tick of the next sample; None while stopped

    def length(self) -> int:
        return sum(log_type_size(op.fetch) for op in self.ops)


class LogService:
    """The log port of one Crazyflie: TOC requests, block commands, and the data of running blocks."""

    def __init__(self, registry: LogParamRegistry):
        self.registry = registry
        self.blocks = {}  # block id -> LogBlock, in creation order
        self.read_errors = 0  # variables whose getter failed (sent as 0)
        self.toc_items_served = 0  # a client with the TOC in its cache asks for none
        self._toc = None

    # -- the TOC --------------------------------------------------------------------------------------------

    def toc(self) -> Toc:
        names = self.registry.log_names()
        if self._toc is None or len(self._toc.entries) != len(names):  # tables only ever grow
            entries = []
            for var_id, full_name in enumerate(names):
                group, name = split_group_and_name(full_name)
                entries.append(TocEntry(group, name, LOG_TYPE_CODES[self.registry.log_get_type(var_id)]))
            self._toc = build_toc(entries)
        return self._toc

    # -- requests -------------------------------------------------------------------------------------------

    def handle(self, packet: CrtpPacket, now: int) -> list[CrtpPacket]:
        if packet.channel == TOC_CH:
            command = field_u8(packet.data, 0)
            if command == CMD_GET_INFO_V2:
                return [self.toc().info_reply(packet, bytes((LOG_MAX_BLOCKS, LOG_MAX_OPS)))]
            if command == CMD_GET_ITEM_V2:
                self.toc_items_served += 1
                return [self.toc().item_reply(packet)]
            return []
        if packet.channel == CONTROL_CH:
            command = field_u8(packet.data, 0)
            block_id = 0 if command == CONTROL_RESET else field_u8(packet.data, 1)
            status = self._control(command, block_id, packet.data, now)
            return [reply(packet, bytes((command, block_id, status)))]
        raise MalformedPacket("log port has no channel %d for a client" % packet.channel)

    def _control(self, command: int, block_id: int, data: bytes, now: int) -> int:
        if command == CONTROL_CREATE_BLOCK_V2:
            return self._create(block_id, data[2:])
        if command == CONTROL_APPEND_BLOCK_V2:
            return self._append(block_id, data[2:])
        if command == CONTROL_DELETE_BLOCK:
            return 0 if self.blocks.pop(block_id, None) is not None else errno.ENOENT
        if command == CONTROL_START_BLOCK:
            return self._start(block_id, 10 * field_u8(data, 2), now)
        if command == CONTROL_START_BLOCK_V2:
            return self._start(block_id, field_u16(data, 2), now)
        if command == CONTROL_STOP_BLOCK:
            block = self.blocks.get(block_id)
            if block is None:
                return errno.ENOENT
            block.next_due = None
            return 0
        if command == CONTROL_RESET:
            self.reset()
            return 0
        return errno.ENOEXEC

    def reset(self) -> None:
        """logReset(): every block deleted (a new client, or the client gone)."""
        self.blocks.clear()

    def _create(self, block_id: int, settings: bytes) -> int:
        if block_id in self.blocks:
            return errno.EEXIST
        if len(self.blocks) >= LOG_MAX_BLOCKS:
            return errno.ENOMEM
        block = LogBlock(block_id)
        status = self._add_ops(block, settings)
        if status == 0:
            self.blocks[block_id] = block
        return status

    def _append(self, block_id: int, settings: bytes) -> int:
        block = self.blocks.get(block_id)
        return errno.ENOENT if block is None else self._add_ops(block, settings)

    def _add_ops(self, block: LogBlock, settings: bytes) -> int:
        """Parse (fetch type, var id) triples (a trailing partial one is ignored, as in the firmware) and add
        them all, or none."""
        count = len(self.registry.log_names())
        new_ops = []
        for offset in range(0, len(settings) - _SETTING_SIZE + 1, _SETTING_SIZE):
            fetch = settings[offset] & 0x0F  # the high nibble is the client's idea of the storage type
            var_id = settings[offset + 1] | settings[offset + 2] << 8
            if log_type_size(fetch) is None:
                return errno.EINVAL
            if var_id == MEMORY_VARIABLE_ID or var_id >= count:
                return errno.ENOENT
            new_ops.append(_Op(var_id, self.registry.log_get_type(var_id), fetch))
        if block.length() + sum(log_type_size(op.fetch) for op in new_ops) > LOG_MAX_LEN:
            return errno.E2BIG
        if sum(len(b.ops) for b in self.blocks.values()) + len(new_ops) > LOG_MAX_OPS:  # a new block has none yet
            return errno.ENOMEM
        block.ops.extend(new_ops)
        return 0

    def _start(self, block_id: int, period_ms: int, now: int) -> int:
        block = self.blocks.get(block_id)
        if block is None:
            return errno.ENOENT
        block.period_ms = period_ms
        block.next_due = now + period_ms  # period 0: one sample, on the next run
        return 0

    # -- data -----------------------------------------------------------------------------------------------

    def next_due(self) -> int | None:
        dues = [b.next_due for b in self.blocks.values() if b.next_due is not None]
        return min(dues) if dues else None

    def due_packets(self, now: int) -> list[CrtpPacket]:
        """One data packet per block due at ``now`` (sampled now), each block rescheduled a period later."""
        packets = []
        for block in self.blocks.values():
            if block.next_due is None or block.next_due > now:
                continue
            packets.append(self._sample(block, now))
            if block.period_ms == 0:
                block.next_due = None
            else:
                block.next_due = max(block.next_due + block.period_ms, now + 1)
        return packets

    def _sample(self, block: LogBlock, now: int) -> CrtpPacket:
        stamp = now & TIMESTAMP_MASK
        data = bytearray((block.id, stamp & 0xFF, (stamp >> 8) & 0xFF, stamp >> 16))
        for op in block.ops:
            data += pack_log_value(self._read(op), op.fetch)
        return CrtpPacket(CRTP_PORT_LOG, LOG_CH, bytes(data))

    def _read(self, op: _Op) -> float | int:
        try:
            if op.storage == LOG_FLOAT:
                return self.registry.log_get_float(op.var_id)
            return self.registry.log_get_int(op.var_id)
        except (ValueError, OverflowError):  # a getter that cannot give a number: the firmware sends its bits
            self.read_errors += 1
            return 0
