"""crtp_supervisor.c (port 9): the supervisor's state for a client, and the arming request.

    ch 0  info     [0x01..0x0B] one state bit -> [0x80 | cmd, bit]
                   [0x0C] the whole bitfield  -> [0x8C, bitfield u16]   (supervisorGetInfoBitfield)
    ch 1  command  [0x01, arm]  -> [0x81, request taken, armed now]     (supervisorRequestArming)
                   [0x02]       -> [0x82, 1, 1]   crash recovery: this supervisor models no crash
                   [0x03] emergency stop, [0x04] its watchdog: not served (the emulated supervisor has no
                   emergency-stop state); dropped and counted as unserved by the server
"""
import struct

from crazyflie_app.firmware.crtp.packet import CrtpPacket, Unserved, field_u8, reply

SUPERVISOR_CH_INFO, SUPERVISOR_CH_COMMAND = 0, 1
CMD_ARM_SYSTEM, CMD_RECOVER_SYSTEM, CMD_EMERGENCY_STOP, CMD_EMERGENCY_STOP_WATCHDOG = 0x01, 0x02, 0x03, 0x04
CMD_FIRST_BIT, CMD_LAST_BIT, CMD_GET_STATE_BITFIELD = 0x01, 0x0B, 0x0C
CMD_RESPONSE = 0x80


class SupervisorService:
    """``cf``: the emulated Crazyflie (``supervisor_get_info_bitfield``, ``supervisor_request_arming``,
    ``supervisor_is_armed``)."""

    def __init__(self, cf):
        self.cf = cf

    def handle(self, packet: CrtpPacket, now: int) -> list[CrtpPacket]:
        command = field_u8(packet.data, 0)
        if packet.channel == SUPERVISOR_CH_INFO:
            bitfield = self.cf.supervisor_get_info_bitfield()
            if command == CMD_GET_STATE_BITFIELD:
                return [reply(packet, struct.pack("<BH", CMD_RESPONSE | command, bitfield))]
            if CMD_FIRST_BIT <= command <= CMD_LAST_BIT:
                return [reply(packet, bytes((CMD_RESPONSE | command, (bitfield >> (command - 1)) & 1)))]
            return []
        if packet.channel == SUPERVISOR_CH_COMMAND:
            if command == CMD_ARM_SYSTEM:
                taken = self.cf.supervisor_request_arming(bool(field_u8(packet.data, 1)))
                return [reply(packet, bytes((CMD_RESPONSE | command, int(taken), int(self.cf.supervisor_is_armed()))))]
            if command == CMD_RECOVER_SYSTEM:
                return [reply(packet, bytes((CMD_RESPONSE | command, 1, 1)))]
            if command in (CMD_EMERGENCY_STOP, CMD_EMERGENCY_STOP_WATCHDOG):
                raise Unserved("emergency stop")
        return []
