"""The camera's serial link: pyserial on a port URL, never blocking, reopening a port that vanished.

``SerialLink(url)`` accepts anything ``serial.serial_for_url`` does: a device (``/dev/ttyS0``), a pty slave
path, or ``loop://`` in tests. The port is opened with ``timeout=0``, so ``poll(now_ms)`` returns at once with
whatever complete lines have arrived (a control task can call it every tick). Bytes go through the serial
grammar's ``LineAssembler``: any terminator (CR, LF, CRLF, NUL) ends a line and a line longer than any valid
message is dropped whole. If the port cannot be opened or fails while reading (unplugged USB-serial adapter,
closed pty), it is closed and reopened later with exponential back-off (``REOPEN_BACKOFF_MS`` doubling up to
``REOPEN_BACKOFF_MAX_MS``); time is passed in, so the back-off is deterministic in simulation.
"""
from collections.abc import Callable
from typing import Any

import serial

from jevois_module.ForaNavTrees.foranav_serial import LineAssembler

REOPEN_BACKOFF_MS = 100
REOPEN_BACKOFF_MAX_MS = 2000
READ_CHUNK = 4096  # bytes per read call; the loop reads until the driver has nothing more


class SerialLink:
    def __init__(self, url: str, baudrate: int = 115200, port_factory: Callable[..., Any] | None = None):
        self.url = url
        self.baudrate = baudrate
        self._factory = port_factory or (lambda: serial.serial_for_url(url, baudrate=baudrate, timeout=0))
        self.port = None
        self.assembler = LineAssembler()
        self.opens = 0
        self.failures = 0
        self.bytes_read = 0
        self.last_error = ""
        self._retry_at_ms = 0
        self._backoff_ms = REOPEN_BACKOFF_MS

    @property
    def is_open(self) -> bool:
        return self.port is not None

    @property
    def lines_dropped(self) -> int:
        return self.assembler.dropped

    def _try_open(self, now_ms: int) -> bool:
        try:
            self.port = self._factory()
        except (serial.SerialException, OSError, ValueError) as err:
            self._failed(now_ms, err)
            return False
        self.opens += 1
        self._backoff_ms = REOPEN_BACKOFF_MS
        self.assembler = LineAssembler(self.assembler.max_length)  # a half line from before is garbage
        return True

    def _failed(self, now_ms: int, err: Exception) -> None:
        self.failures += 1
        self.last_error = str(err)
        if self.port is not None:
            try:
                self.port.close()
            except (serial.SerialException, OSError):
                pass
        self.port = None
        self._retry_at_ms = now_ms + self._backoff_ms
        self._backoff_ms = min(2 * self._backoff_ms, REOPEN_BACKOFF_MAX_MS)

    def poll(self, now_ms: int) -> list[bytes]:
        """Complete lines (bytes) received since the last poll; [] if none or the port is down."""
        if self.port is None and (now_ms < self._retry_at_ms or not self._try_open(now_ms)):
            return []
        lines = []
        try:
            while True:
                data = self.port.read(READ_CHUNK)
                if not data:
                    break
                self.bytes_read += len(data)
                lines.extend(self.assembler.feed(data))
                if len(data) < READ_CHUNK:
                    break
        except (serial.SerialException, OSError) as err:
            self._failed(now_ms, err)
        return lines

    def close(self) -> None:
        if self.port is not None:
            try:
                self.port.close()
            finally:
                self.port = None
