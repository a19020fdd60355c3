"""The camera link of the Python app over the emulated UART2 (what the app reads on the Bolt).

``Uart2Link(cf)`` has the interface of ``serial_link.SerialLink`` (``poll(now_ms)`` -> complete lines,
``lines_dropped``, ``opens``, ``is_open``, ``close()``), but its bytes come from the firmware's UART2 driver
(``cf.uart2_get_data_with_timeout``), so they went through the 200-byte receive buffer that drops bytes
when the app reads too rarely. The harness plugs the camera's pty into ``cf.attach_uart2`` first.
"""
from crazyflie_app.firmware.system import Crazyflie
from jevois_module.ForaNavTrees.foranav_serial import LineAssembler

UART2_BAUDRATE = 115200
READ_CHUNK = 64  # bytes per uart2GetDataWithTimeout call, as the C app's buffer
READ_TIMEOUT_TICKS = 1  # 0 would return nothing (uart2.c); 1 tick is the shortest wait


class Uart2Link:
    def __init__(self, cf: Crazyflie):
        if cf.uart2 is None:
            raise ValueError("Uart2Link: nothing attached to UART2 (cf.attach_uart2(url) first)")
        self.cf = cf
        self.assembler = LineAssembler()
        self.bytes_read = 0
        cf.uart2_init(UART2_BAUDRATE)

    port = property(lambda self: self.cf.uart2)
    is_open = property(lambda self: True)
    opens = property(lambda self: self.cf.uart2.opens)
    lines_dropped = property(lambda self: self.assembler.dropped)

    def poll(self, now_ms: int) -> list[bytes]:
        """Complete lines (bytes) received since the last poll."""
        lines = []
        while True:
            data = self.cf.uart2_get_data_with_timeout(READ_CHUNK, READ_TIMEOUT_TICKS)
            if not data:
                return lines
            self.bytes_read += len(data)
            lines.extend(self.assembler.feed(data))

    def close(self) -> None:
        self.cf.uart2.close()
