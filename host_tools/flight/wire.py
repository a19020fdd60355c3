"""The serial wire between the camera and the flight controller: a real pseudo-terminal.

``PtyWire()`` opens a pty pair in raw mode; the app's serial link opens ``slave_path`` with pyserial like a
UART, and the harness writes the camera's bytes into the master side. In lockstep mode ``write`` returns
only once the bytes are readable on the slave side (ioctl FIONREAD), so the simulated clock never runs ahead
of the kernel and a run is deterministic: same map and seed, same bytes read at the same simulated ticks.
The wait sleeps in poll() until the kernel hands the first byte over (it used to spin on FIONREAD, which cost
a vision flight about a second of system time), and naps briefly while the rest follows.
"""
import fcntl
import os
import select
import struct
import termios
import time
import tty

LOCKSTEP_TIMEOUT_S = 5.0  # wall-clock limit for bytes to cross the pty (normally microseconds)
POLL_SLICE_MS = 100  # one poll() while waiting for the first byte (the deadline is checked between slices)
PARTIAL_NAP_S = 20e-6  # the first bytes are there, the rest is on its way


class WireError(RuntimeError):
    pass


class PtyWire:
    def __init__(self, lockstep: bool = True):
        self.master_fd, self.slave_fd = os.openpty()
        tty.setraw(self.slave_fd)
        attrs = termios.tcgetattr(self.slave_fd)
        attrs[3] &= ~termios.ECHO  # no echo back into the master (nobody reads it)
        termios.tcsetattr(self.slave_fd, termios.TCSANOW, attrs)
        self.slave_path = os.ttyname(self.slave_fd)
        self.lockstep = lockstep
        self.bytes_written = 0
        self._readable = select.poll()
        self._readable.register(self.slave_fd, select.POLLIN)

    def pending(self) -> int:
        """Bytes written but not yet read on the slave side."""
        buf = fcntl.ioctl(self.slave_fd, termios.FIONREAD, struct.pack("i", 0))
        return struct.unpack("i", buf)[0]

    def write(self, data: bytes) -> None:
        if not data:
            return
        before = self.pending() if self.lockstep else 0
        view = memoryview(data)
        while view:
            written = os.write(self.master_fd, view)
            view = view[written:]
        self.bytes_written += len(data)
        if self.lockstep:
            self._wait_readable(before + len(data))

    def _wait_readable(self, count: int) -> None:
        """Return once ``count`` bytes are readable on the slave side (WireError after LOCKSTEP_TIMEOUT_S)."""
        deadline = time.monotonic() + LOCKSTEP_TIMEOUT_S
        while True:
            have = self.pending()
            if have >= count:
                return
            if time.monotonic() > deadline:
                raise WireError("pty: %d bytes did not reach the slave side" % (count - have))
            if have == 0:
                self._readable.poll(POLL_SLICE_MS)  # sleeps until the kernel delivers the first byte
            else:
                time.sleep(PARTIAL_NAP_S)

    def close(self) -> None:
        for fd in (self.master_fd, self.slave_fd):
            try:
                os.close(fd)
            except OSError:
                pass
        self.master_fd = self.slave_fd = -1

    def __enter__(self) -> "PtyWire":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
