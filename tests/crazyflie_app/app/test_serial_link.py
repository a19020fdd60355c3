"""The camera serial link: non-blocking reads, partial and overlong lines, reopening a vanished port."""
import serial

from crazyflie_app.app.serial_link import REOPEN_BACKOFF_MS, SerialLink
from host_tools.flight.wire import PtyWire


def loop_link():
    link = SerialLink("loop://")
    assert link.poll(0) == []  # opens the port, nothing there yet
    return link


def test_that_the_port_is_opened_non_blocking():
    link = loop_link()
    assert link.is_open and link.port.timeout == 0


def test_that_complete_lines_come_out_with_any_terminator():
    link = loop_link()
    link.port.write(b"T2 10 -20\r\nMARK STOP\nALIVE\r")
    assert link.poll(10) == [b"T2 10 -20", b"MARK STOP", b"ALIVE"]


def test_that_a_line_split_across_reads_is_reassembled():
    link = loop_link()
    link.port.write(b"N2 oil_palm 12")
    assert link.poll(10) == []
    link.port.write(b"0 -40 300 200\r\n")
    assert link.poll(20) == [b"N2 oil_palm 120 -40 300 200"]


def test_that_an_overlong_line_is_dropped_whole_and_the_next_line_survives():
    link = loop_link()
    link.port.write(b"T2 " + b"9" * 500 + b"\r\nT2 1 2\r\n")
    assert link.poll(10) == [b"T2 1 2"]
    assert link.lines_dropped == 1


class FlakyPort(object):
    """A port that fails on its first read, like an unplugged USB-serial adapter."""

    timeout = 0

    def __init__(self, payload, fail):
        self.payload, self.fail, self.closed = payload, fail, False

    def read(self, size):
        if self.fail:
            raise serial.SerialException("device reports readiness to read but returned no data")
        data, self.payload = self.payload, b""
        return data

    def close(self):
        self.closed = True


def test_that_a_failing_port_is_closed_and_reopened_with_back_off():
    # Fixture: open fails at t=0, the port fails on read at t=100, then a good port appears
    attempts = []
    ports = [serial.SerialException("no such device"), FlakyPort(b"", fail=True),
             serial.SerialException("busy"), FlakyPort(b"T2 0 0\r\n", fail=False)]

    def factory():
        attempts.append(len(attempts))
        item = ports.pop(0)
        if isinstance(item, Exception):
            raise item
        return item

    sut = SerialLink("/dev/ttyFAKE", port_factory=factory)
    # Test / Assert
    assert sut.poll(0) == [] and not sut.is_open
    assert sut.poll(REOPEN_BACKOFF_MS - 1) == [] and len(attempts) == 1  # waiting out the back-off
    assert sut.poll(REOPEN_BACKOFF_MS) == [] and not sut.is_open  # opened, then the read failed
    assert sut.failures == 2
    retry = 2 * REOPEN_BACKOFF_MS  # a successful open reset the back-off
    assert sut.poll(retry - 1) == [] and len(attempts) == 2
    assert sut.poll(retry) == [] and len(attempts) == 3  # 'busy': the back-off doubles
    assert sut.poll(retry + 2 * REOPEN_BACKOFF_MS - 1) == [] and len(attempts) == 3
    assert sut.poll(retry + 2 * REOPEN_BACKOFF_MS) == [b"T2 0 0"]
    assert sut.opens == 2


def test_that_a_vanished_pty_is_detected_and_retried():
    wire = PtyWire()
    sut = SerialLink(wire.slave_path)
    assert sut.poll(0) == [] and sut.is_open  # pyserial flushes input on open: open first
    wire.write(b"T2 5 5\r\n")
    assert sut.poll(0) == [b"T2 5 5"]
    wire.close()  # the other end goes away
    assert sut.poll(10) == []
    assert not sut.is_open and sut.failures == 1
    assert sut.poll(10 + REOPEN_BACKOFF_MS) == []  # the path is gone: reopening fails, no exception
    assert sut.failures == 2
    sut.close()
