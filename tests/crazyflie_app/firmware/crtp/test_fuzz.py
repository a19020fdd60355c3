"""Bad input over the wire: random, malformed, truncated, oversized and out-of-order datagrams, unknown ports
and channels, a flood, a client that vanishes. The flight goes on, nothing raises, memory stays bounded, and
stock cflib still connects afterwards.

The datagrams leave out only the well-formed commands a client is entitled to give and that change a flight
by design (a param write, arming or disarming, giving the commander back): those are commands, not noise,
and the client owns them (``_is_command``). Everything else, random bytes included, is fair game.
"""
import random
import socket
import threading
import time
import tracemalloc
from pathlib import Path

import pytest

from crazyflie_app.firmware import Crazyflie
from crazyflie_app.firmware.crtp import CrtpServer, console_service, log_service, packet
from crazyflie_app.firmware.crtp.values import param_size
from host_tools.flight.harness import Flight
from host_tools.flight.registry import camera_factory
from host_tools.maps import load_map
from tests.crazyflie_app.firmware.crtp.conftest import Session, wait_for

DEFAULT_DATAGRAMS = 100_000
SLOW_DATAGRAMS = 400_000
FLOOD_DATAGRAMS = 5_000
SENDERS = 4
BURST = 150  # datagrams sent before waiting for the server to read them (its socket buffer holds ~270)
CATCH_UP_S = 0.5
FUZZ_SEED = 31
# A slower cruise makes the mission last longer than the fuzz: the clock moves on by about a second of flight
# time per second of fuzzing (the hold's refill), 50-70 s for the default suite's fuzz on this machine (mission
# 172 s at 0.05 m/s against 113 s at the map's speed), several minutes for the slow one (631 s at 0.01 m/s)
DEFAULT_CRUISE_MPS, SLOW_CRUISE_MPS = 0.05, 0.01
# what the server allocates while it reads a window of datagrams and still holds at the window's end: its
# bounded state (log blocks, console backlog) at most; a leak of a few bytes per datagram would exceed it
MEMORY_GROWTH_MAX_BYTES = 64 * 1024
DEFAULT_WINDOW = (40_000, 70_000)  # tracemalloc slows the interpreter a few times: a window in the default suite
CRTP_PACKAGE = str(Path(packet.__file__).parent)
KNOWN_COMMAND_PORTS = (0x02, 0x03, 0x04, 0x05, 0x07, 0x09, 0x0D, 0x0F)


def _writable_sizes(registry) -> dict[int, int]:
    """param id -> value size, for the params a client may write."""
    return {index: param_size(entry.type) for index, (_, entry) in enumerate(registry.param_entries())
            if not entry.read_only}


def _is_command(datagram: bytes, writable: dict[int, int]) -> bool:
    """A well-formed command that changes the flight on purpose (see the module docstring)."""
    if not 2 <= len(datagram) <= 31:
        return False
    port, channel, data = datagram[0] >> 4, datagram[0] & 0x03, datagram[1:]
    if port == 0x02 and channel == 2 and len(data) >= 2:  # param write to a real, writable param
        size = writable.get(data[0] | data[1] << 8)
        return size is not None and len(data) == 2 + size
    if port == 0x02 and channel == 3 and data[0] == 0:  # set by name: any that parses
        return data.count(0) >= 3
    if port == 0x09 and channel == 1 and data[0] == 0x01 and len(data) >= 2:  # arm / disarm
        return True
    if port == 0x0D and channel == 0 and data[0] == 0x01 and len(data) >= 2:  # deprecated arm / disarm
        return True
    return port == 0x07 and channel == 1 and data[0] == 0 and len(data) == 5  # notifySetpointsStop


def _structured(rng: random.Random) -> bytes:
    """A datagram that looks like a request: a known port, a plausible command, a payload that is not."""
    port = rng.choice(KNOWN_COMMAND_PORTS + (0x01, 0x06, 0x08, 0x0A, 0x0B, 0x0C, 0x0E))
    channel = rng.randrange(4)
    kind = rng.random()
    if kind < 0.3:  # a command byte and a truncated or overlong rest
        data = bytes([rng.randrange(16)]) + bytes(rng.randrange(256) for _ in range(rng.randrange(8)))
    elif kind < 0.5 and port == 0x05:  # log block commands out of order, odd ids, odd periods, bad variables
        command = rng.choice((2, 3, 4, 5, 6, 7, 8, 0, 1, 9))
        block = rng.choice((0, 1, 2, 255, rng.randrange(256)))
        settings = b"".join(bytes([rng.choice((1, 2, 3, 4, 5, 6, 7, 8, 0, 0x77, 0xF9)),
                                   rng.randrange(64), rng.choice((0, 0, 0xFF))]) for _ in range(rng.randrange(10)))
        data = bytes([command, block]) + (settings if command in (6, 7) else
                                          bytes(rng.randrange(256) for _ in range(rng.randrange(4))))
        channel = 1
    elif kind < 0.6:  # oversized
        data = bytes(rng.randrange(256) for _ in range(rng.randrange(31, 64)))
    elif kind < 0.65:  # empty payload
        data = b""
    else:
        data = bytes(rng.randrange(256) for _ in range(rng.randrange(31)))
    return bytes([port << 4 | rng.choice((0, 0x0C)) | channel]) + data


def fuzz_datagrams(rng: random.Random, count: int, writable: dict[int, int]):
    """``count`` datagrams: a third uniformly random (length 0..40), the rest structured; no commands."""
    made = 0
    while made < count:
        if rng.random() < 0.33:
            datagram = bytes(rng.randrange(256) for _ in range(rng.randrange(41)))
        else:
            datagram = _structured(rng)
        if not _is_command(datagram, writable):
            made += 1
            yield datagram


class _FlightThread(threading.Thread):
    def __init__(self, flight: Flight):
        super().__init__(daemon=True)
        self.flight, self.error = flight, None

    def run(self):
        try:
            self.flight.run()
        except BaseException as err:  # noqa: BLE001 - the test asserts there is none
            self.error = err


def _crtp_allocations() -> int:
    snapshot = tracemalloc.take_snapshot().filter_traces([tracemalloc.Filter(True, CRTP_PACKAGE + "/*")])
    return sum(stat.size for stat in snapshot.statistics("filename"))


def _fuzz_a_flight(tmp_path, datagrams: int, window: tuple[int, int], cruise_mps: float) -> None:
    """Fuzz a flight with ``datagrams`` datagrams, tracing the server's allocations over the ``window``
    (datagram numbers) of them."""
    pmap = load_map("map1")
    flight = Flight(pmap, camera_factory("oracle")(pmap, seed=0), seed=0, out_dir=tmp_path / "flight",
                    options={"crtp": "127.0.0.1:0", "params": {"app.cruiseSpeed": cruise_mps}})
    server = flight.crtp
    writable = _writable_sizes(flight.rig.cf.registry)
    senders = [socket.socket(socket.AF_INET, socket.SOCK_DGRAM) for _ in range(SENDERS)]
    rng = random.Random(FUZZ_SEED)
    thread = _FlightThread(flight)
    held = None
    try:
        thread.start()
        wait_for(lambda: flight.rig.now() > 6000, what="take-off")  # the app holds the commander
        sent = 0
        for datagram in fuzz_datagrams(rng, datagrams, writable):
            try:
                rng.choice(senders).sendto(datagram, server.address)
            except OSError:
                pass
            sent += 1
            if sent == window[0]:
                tracemalloc.start()
            elif sent == window[1]:
                held = _crtp_allocations()
                tracemalloc.stop()
            if sent % BURST == 0:
                deadline = time.monotonic() + CATCH_UP_S
                while server.stats.datagrams < sent - BURST // 2 and time.monotonic() < deadline and thread.is_alive():
                    time.sleep(0.0005)
        for _ in range(FLOOD_DATAGRAMS):  # a flood: no pacing at all (the socket buffer drops the excess)
            senders[1].sendto(bytes([rng.randrange(256)]) * rng.randrange(1, 40), server.address)
        # a client that vanishes: a 10 ms block of six estimate variables, then silence
        senders[0].sendto(bytes([0x51, 6, 7]) + b"".join(bytes([7, i, 0]) for i in range(6)), server.address)
        senders[0].sendto(bytes([0x51, 3, 7, 1]), server.address)
        wait_for(lambda: server.stats.lost_clients >= 1, timeout_s=10, what="the vanished client given up")
        # Assert: a real client still gets served, mid-flight
        assert thread.is_alive(), "the flight ended during the fuzz"
        session = Session(server.uri, tmp_path / "toc_cache").wait()
        samples = session.start_block("after", 100, ("stateEstimate.z",))
        wait_for(lambda: len(samples) >= 5, what="log data after the fuzz")
        session.close()
        thread.join(600)
    finally:
        tracemalloc.stop()
        for s in senders:
            s.close()
        flight.close()
    summary = flight.summary()
    assert thread.error is None, repr(thread.error)
    assert summary["completed"] and summary["success"], "the flight did not go on as it would have"
    assert server.stats.datagrams >= datagrams, "the fuzz datagrams were not all read"
    assert server.stats.malformed > datagrams // 10
    assert server.stats.unknown_port > 0 and server.stats.unserved > 0
    assert server.stats.lost_clients >= 1, "the vanished client was never given up"
    assert len(server.log.blocks) <= log_service.LOG_MAX_BLOCKS
    assert len(server.console.pending) <= console_service.CONSOLE_BACKLOG_PACKETS
    assert held is not None and held < MEMORY_GROWTH_MAX_BYTES, "the server's memory grew with the datagrams"


def test_that_a_flight_goes_on_through_100000_bad_datagrams(tmp_path):
    _fuzz_a_flight(tmp_path, DEFAULT_DATAGRAMS, DEFAULT_WINDOW, DEFAULT_CRUISE_MPS)


@pytest.mark.slow
def test_that_a_flight_goes_on_through_400000_bad_datagrams(tmp_path):
    _fuzz_a_flight(tmp_path, SLOW_DATAGRAMS, (SLOW_DATAGRAMS // 10, SLOW_DATAGRAMS), SLOW_CRUISE_MPS)


def test_that_no_short_datagram_makes_the_server_raise():
    """Every header byte with payloads of 0..3 bytes, straight into the dispatch (no socket, no flight)."""
    cf = Crazyflie()
    server = CrtpServer(cf, "127.0.0.1", 0)
    rng = random.Random(FUZZ_SEED)
    writable = _writable_sizes(cf.registry)
    handled = 0
    try:
        for header in range(256):
            for length in range(4):
                for _ in range(3 if length else 1):
                    datagram = bytes([header]) + bytes(rng.randrange(256) for _ in range(length))
                    if not _is_command(datagram, writable):
                        server.handle_datagram(datagram, ("127.0.0.1", 9), 0)
                        handled += 1
    finally:
        server.close()
    assert server.stats.datagrams == handled
    assert server.stats.malformed > 0 and server.stats.replies > 0
    assert not cf.supervisor_is_armed()
