"""platformservice.c (port 13): what a client asks about the platform, and the deprecated platform commands.

    ch 1  version   [0] -> [0, CRTP_PROTOCOL_VERSION i32]   (cflib asks on connect; 12 = firmware 2a18fc29)
                    [1] -> [1, firmware version text]       [2] -> [2, device type name]
    ch 0  command   [1, arm] deprecated arming (a console warning, then as the supervisor port: [1, ok, armed])
                    [2] deprecated crash recovery -> [2, 1, 1] (this supervisor models no crash)
                    [0, on] continuous-wave test: echoed, there is no radio to key
                    [3, kind] user notification: an empty reply, there are no LEDs
                    anything else: echoed, as the firmware sends the packet back
    ch 2  app channel: not served (the ForaNav app does not use it)
"""
import struct

from crazyflie_app.firmware.crtp.packet import CrtpPacket, field_u8, reply

CRTP_PROTOCOL_VERSION = 12  # crtp.h of the firmware the emulation follows
FIRMWARE_VERSION = "2a18fc29 emulated"  # V_STAG: the firmware revision, and what this is
PLATFORM_COMMAND_CH, VERSION_CH = 0, 1
SET_CONTINUOUS_WAVE, ARM_SYSTEM, RECOVER_SYSTEM, USER_NOTIFICATION = 0, 1, 2, 3
GET_PROTOCOL_VERSION, GET_FIRMWARE_VERSION, GET_DEVICE_TYPE_NAME = 0, 1, 2
DEBUG_MODULE = "PLAT"


class PlatformService:
    """``cf``: the emulated Crazyflie (``supervisor_request_arming``, ``supervisor_is_armed``,
    ``platform_config_get_device_type_name``, ``debug_print``)."""

    def __init__(self, cf):
        self.cf = cf

    def handle(self, packet: CrtpPacket, now: int) -> list[CrtpPacket]:
        if packet.channel == VERSION_CH:
            return self._version(packet)
        if packet.channel == PLATFORM_COMMAND_CH:
            return [self._command(packet)]
        return []

    def _version(self, packet: CrtpPacket) -> list[CrtpPacket]:
        command = field_u8(packet.data, 0)
        if command == GET_PROTOCOL_VERSION:
            return [reply(packet, struct.pack("<Bi", command, CRTP_PROTOCOL_VERSION))]
        if command == GET_FIRMWARE_VERSION:
            return [reply(packet, bytes((command,)) + FIRMWARE_VERSION.encode("ascii"))]
        if command == GET_DEVICE_TYPE_NAME:
            name = self.cf.platform_config_get_device_type_name()
            return [reply(packet, bytes((command,)) + name.encode("ascii"))]
        return []

    def _command(self, packet: CrtpPacket) -> CrtpPacket:
        command = field_u8(packet.data, 0)
        if command == ARM_SYSTEM:
            self.cf.debug_print(DEBUG_MODULE, "WARNING: arming via platform port is deprecated, use supervisor port")
            success = len(packet.data) >= 2 and self.cf.supervisor_request_arming(bool(packet.data[1]))
            return reply(packet, bytes((command, int(success), int(self.cf.supervisor_is_armed()))))
        if command == RECOVER_SYSTEM:
            self.cf.debug_print(DEBUG_MODULE, "WARNING: recovery via platform port is deprecated, use supervisor port")
            return reply(packet, bytes((command, 1, 1)))
        if command == USER_NOTIFICATION:
            return reply(packet, b"")
        return reply(packet, packet.data)
