"""The transport: cflib's ``udp://HOST:PORT`` link (one CRTP packet per datagram), and the downlink's budget.

``UdpLink`` is a non-blocking UDP socket bound to HOST:PORT: ``receive()`` returns one datagram or None,
``send()`` never blocks and never raises (a client that went away is the client's problem, as a radio that
went out of range), ``wait_readable(s)`` sleeps until a datagram is there or ``s`` seconds passed. A datagram
is read with a buffer a little larger than a CRTP packet, so an oversized one arrives truncated to a length
no packet has, and is dropped as such.

``DownlinkBudget`` is the radio link's capacity for what the Crazyflie sends on its own (log data, console
text): ``LINK_PACKETS_PER_S`` packets a second, in bursts of at most ``TX_QUEUE_PACKETS`` (the firmware's
CRTP TX queue). Replies to requests do not draw on it: a client asks at its own pace.
"""
import select
import socket
import time
from collections.abc import Callable

from crazyflie_app.firmware.crtp.packet import CRTP_MAX_DATA_SIZE

RECEIVE_BUFFER = 2 * (CRTP_MAX_DATA_SIZE + 1)
# About a Crazyradio's downlink, and a rate cflib's UDP driver and cfclient's plots take without loss
# (cflib's receive thread alone starts dropping near 10 000 datagrams/s on this machine: docs/crtp.md).
LINK_PACKETS_PER_S = 1000
TX_QUEUE_PACKETS = 200  # crtp.c: CRTP_TX_QUEUE_SIZE

Address = tuple[str, int]


class UdpLink:
    """A bound, non-blocking UDP socket (OSError from ``bind`` propagates: the caller names the endpoint)."""

    def __init__(self, host: str, port: int):
        self._sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            self._sock.setblocking(False)
            self._sock.bind((host, port))
        except BaseException:
            self._sock.close()
            raise
        self.send_errors = 0

    @property
    def address(self) -> Address:
        return self._sock.getsockname()

    def receive(self) -> tuple[bytes, Address] | None:
        try:
            return self._sock.recvfrom(RECEIVE_BUFFER)
        except (BlockingIOError, InterruptedError):
            return None
        except OSError:  # an ICMP error of an earlier send, reported here: nothing to read
            return None

    def wait_readable(self, timeout_s: float) -> bool:
        if timeout_s <= 0:
            return False
        readable, _, _ = select.select([self._sock], [], [], timeout_s)
        return bool(readable)

    def send(self, datagram: bytes, address: Address) -> bool:
        try:
            self._sock.sendto(datagram, address)
            return True
        except OSError:  # full buffers, an unreachable or vanished client
            self.send_errors += 1
            return False

    def close(self) -> None:
        self._sock.close()


class DownlinkBudget:
    """A token bucket: ``rate`` packets a second, holding at most ``burst`` (starts full)."""

    def __init__(self, rate: float = LINK_PACKETS_PER_S, burst: int = TX_QUEUE_PACKETS,
                 clock: Callable[[], float] = time.monotonic):
        self.rate, self.burst, self.clock = float(rate), float(burst), clock
        self._tokens = self.burst
        self._at = clock()

    def _refill(self) -> None:
        now = self.clock()
        self._tokens = min(self.burst, self._tokens + (now - self._at) * self.rate)
        self._at = now

    def take(self) -> bool:
        """Spend one packet's worth if there is one."""
        self._refill()
        if self._tokens >= 1.0:
            self._tokens -= 1.0
            return True
        return False

    def seconds_to_next(self) -> float:
        self._refill()
        return max(0.0, (1.0 - self._tokens) / self.rate)
