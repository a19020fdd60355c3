"""uart2.c: the deck-port UART the camera talks to, with the firmware's 200-byte receive buffer.

On the Bolt the USART2 receive interrupt pushes each byte into a 200-byte stream buffer
(``xStreamBufferCreate(200, 1)``) and a full buffer drops the byte silently; the app takes bytes out with
``uart2GetDataWithTimeout(size, buffer, timeoutTicks)``. Here:

* the wire is a real serial port (the harness' pty) read by the RX task every ``RX_POLL_MS`` (the
  resolution of arrival times: polling at 1 ms made every flight 50 % more expensive, for nothing the app
  could see when it reads every 10 ms); bytes found there arrive one by one at the line rate (10 bits a
  byte at ``baudrate``:
  115200 baud = 11.52 bytes per ms), so a frame of 8 T2 lines + MARK STOP (123 bytes) takes 10.7 ms to
  come in, as on the wire;
* arrived bytes go into the 200-byte buffer, or are dropped (counted in ``dropped_bytes``, the firmware
  only sets its overrun flag) when it is full;
* ``uart2_get_data_with_timeout(size, timeout_ticks)`` returns up to ``size`` bytes that have arrived. As
  the firmware's loop ``while (sizeLeft > 0 && timeoutEnd > xTaskGetTickCount())``, a timeout of 0 returns
  nothing; a task cannot block inside a call here, so any timeout >= 1 returns what is there at once
  (the task then sleeps with vTaskDelay, as the C app does between reads).

A reader that falls behind (reads less often than the buffer fills) loses bytes exactly there.
"""
import fcntl
import os
import struct
import termios

from crazyflie_app.firmware.freertos import Scheduler, Task, v_task_delay

RX_BUFFER_BYTES = 200  # uart2.c: xStreamBufferCreate(200, 1)
DEFAULT_BAUDRATE = 115200
BITS_PER_BYTE = 10  # 8N1: start + 8 data + stop
RX_POLL_MS = 5
READ_CHUNK = 4096
REOPEN_MS = 100


class Uart2:
    """The UART2 peripheral and driver of one emulated Crazyflie, wired to ``url`` (a pty slave path)."""

    def __init__(self, clock: Scheduler, url: str, baudrate: int = DEFAULT_BAUDRATE,
                 rx_buffer_bytes: int = RX_BUFFER_BYTES):
        self._clock = clock
        self.url = url
        self.baudrate = baudrate
        self.rx_buffer_bytes = int(rx_buffer_bytes)
        self._fd = None
        self._retry_at = 0
        self._rx = bytearray()  # the stream buffer
        self._line = bytearray()  # bytes on the wire, not yet shifted in
        self._next_arrival_ms = 0.0  # when the first byte of _line completes
        self.received_bytes = 0  # into the buffer
        self.dropped_bytes = 0  # lost to a full buffer
        self.overrun = False  # uart2DidOverrun()
        self.opens = 0
        self.failures = 0
        self.initialized = False

    @property
    def byte_time_ms(self) -> float:
        return 1000.0 * BITS_PER_BYTE / self.baudrate

    def uart2_init(self, baudrate: int) -> None:
        """uart2Init(baudrate): the app sets the line rate (115200 for the JeVois)."""
        self.baudrate = int(baudrate)
        self.initialized = True

    # -- the wire side ----------------------------------------------------------------------------------------

    def _open(self, now):
        try:
            self._fd = os.open(self.url, os.O_RDWR | os.O_NONBLOCK | os.O_NOCTTY)
        except OSError:
            self.failures += 1
            self._retry_at = now + REOPEN_MS
            return False
        self.opens += 1
        return True

    def _pending_on_wire(self):
        try:
            return struct.unpack("i", fcntl.ioctl(self._fd, termios.FIONREAD, b"\0\0\0\0"))[0]
        except OSError:
            return 1  # not a tty: let the read find out

    def _read_wire(self, now):
        if self._fd is None and (now < self._retry_at or not self._open(now)):
            return
        if not self._pending_on_wire():
            return
        try:
            while True:
                data = os.read(self._fd, READ_CHUNK)
                if not data:
                    break
                if not self._line:
                    self._next_arrival_ms = max(self._next_arrival_ms, now + self.byte_time_ms)
                self._line.extend(data)
                if len(data) < READ_CHUNK:
                    break
        except BlockingIOError:
            pass
        except OSError:
            self.failures += 1
            self.close()
            self._retry_at = now + REOPEN_MS

    def _shift_in(self, now):
        """Move the bytes that have arrived by ``now`` into the buffer (dropping what does not fit)."""
        if not self._line or now < self._next_arrival_ms:
            return
        step = self.byte_time_ms
        count = min(len(self._line), int((now - self._next_arrival_ms) / step) + 1)
        arrived = self._line[:count]
        del self._line[:count]
        self._next_arrival_ms += count * step
        room = self.rx_buffer_bytes - len(self._rx)
        if count > room:
            self.dropped_bytes += count - max(room, 0)
            self.overrun = True
            arrived = arrived[:max(room, 0)]
        self._rx.extend(arrived)
        self.received_bytes += len(arrived)

    def rx_task(self) -> Task:
        """The USART2 RX interrupt, as a task: poll the wire, shift bytes in at the line rate."""
        while True:
            now = self._clock.x_task_get_tick_count()
            # bytes due by now go in first, so new ones queue behind the line's busy time, not before it
            self._shift_in(now)
            self._read_wire(now)
            yield v_task_delay(RX_POLL_MS)

    # -- the app side -----------------------------------------------------------------------------------------

    def uart2_get_data_with_timeout(self, size: int, timeout_ticks: int) -> bytes:
        """Up to ``size`` received bytes (b"" if none, or if ``timeout_ticks`` is 0, as in uart2.c)."""
        if timeout_ticks <= 0 or size <= 0:
            return b""
        self._shift_in(self._clock.x_task_get_tick_count())
        data = bytes(self._rx[:size])
        del self._rx[:size]
        return data

    def uart2_did_overrun(self) -> bool:
        result, self.overrun = self.overrun, False
        return result

    def bytes_waiting(self) -> int:
        return len(self._rx)

    def close(self) -> None:
        if self._fd is not None:
            try:
                os.close(self._fd)
            except OSError:
                pass
            self._fd = None
