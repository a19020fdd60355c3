"""console.c over CRTP (port 0, channel 0): the DEBUG_PRINT lines of the app and the firmware, for a client.

A line goes out as the firmware prints it, ``"MODULE: text\\n"``, cut into packets of at most 30 bytes (the
console flushes on a newline or a full packet). Text is sent as ASCII (anything else as '?'), so a packet
never splits a character and cflib's UTF-8 decoding cannot fail. Lines wait in a bounded backlog until a
client takes them: a client that connects sees the latest lines from before it came, as the firmware's TX
queue keeps them; when the backlog is full the oldest packets go first (counted in ``dropped``).
"""
from collections import deque

from crazyflie_app.firmware.crtp.packet import CRTP_MAX_DATA_SIZE, CRTP_PORT_CONSOLE, CrtpPacket

CONSOLE_BACKLOG_PACKETS = 64


class ConsoleService:
    """Taps ``console.listeners`` (the emulated Crazyflie's console) while attached."""

    def __init__(self, console, backlog_packets: int = CONSOLE_BACKLOG_PACKETS):
        self.console = console
        self.pending = deque()
        self.backlog_packets = backlog_packets
        self.dropped = 0
        console.listeners.append(self._on_line)

    def _on_line(self, tick: int, module: str, text: str) -> None:
        data = ("%s: %s\n" % (module, text)).encode("ascii", "replace")
        for start in range(0, len(data), CRTP_MAX_DATA_SIZE):
            if len(self.pending) >= self.backlog_packets:
                self.pending.popleft()
                self.dropped += 1
            self.pending.append(CrtpPacket(CRTP_PORT_CONSOLE, 0, data[start:start + CRTP_MAX_DATA_SIZE]))

    def detach(self) -> None:
        if self._on_line in self.console.listeners:
            self.console.listeners.remove(self._on_line)
