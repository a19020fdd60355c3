"""crtp_commander_high_level.c over CRTP (port 8): takeoff, land, go_to, start_trajectory, stop,
define_trajectory, ... run by the firmware's own high-level commander (the firmware plant compiles it with
planner.c and pptraj.c).

    ch 0  [command, ...]  -> [command, data[1], data[2], result]   (0, or ENOEXEC / EINVAL ... as it answers)

as its CRTP task answers: the request's first three bytes with ``data[3]`` the result (a request shorter than
three bytes gets zeros there: the packet buffer's bytes). An unknown command is the firmware's ENOEXEC, a
trajectory id past its table ENOEXEC, a start of an undefined or oversized trajectory EINVAL. An empty packet,
which the task would read as the previous packet's command, is dropped (MalformedPacket).
"""
from crazyflie_app.firmware.crtp.packet import CrtpPacket, MalformedPacket, reply

ANSWER_SIZE = 4


class HighLevelService:
    """``high_level``: the Crazyflie's high-level commander (``command(payload) -> int``)."""

    def __init__(self, high_level):
        self.high_level = high_level
        self.commands = 0
        self.refused = 0  # answered with a nonzero result

    def handle(self, packet: CrtpPacket, now: int) -> list[CrtpPacket]:
        if not packet.data:
            raise MalformedPacket("high-level command without a command byte")
        result = self.high_level.command(packet.data)
        self.commands += 1
        self.refused += result != 0
        head = (packet.data[:ANSWER_SIZE - 1] + bytes(ANSWER_SIZE - 1))[:ANSWER_SIZE - 1]
        return [reply(packet, head + bytes((result & 0xFF,)))]
