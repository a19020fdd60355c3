"""The server over a real UDP socket: who the client is, when the clock waits, and what realtime drops."""
import socket

import pytest

from crazyflie_app.firmware import Crazyflie, v_task_delay
from crazyflie_app.firmware.crtp import CrtpServer
from crazyflie_app.firmware.crtp.link import DownlinkBudget

RUN_MS = 2000
RECEIVE_TIMEOUT_S = 2.0


@pytest.fixture
def client():
    sockets = []

    def make():
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        sock.bind(("127.0.0.1", 0))
        sock.settimeout(RECEIVE_TIMEOUT_S)
        sockets.append(sock)
        return sock

    yield make
    for sock in sockets:
        sock.close()


def _served(lockstep=True):
    cf = Crazyflie()
    server = CrtpServer(cf, "127.0.0.1", 0, lockstep=lockstep)
    server.start()
    return cf, server


def _z_block(cf, period_10ms):
    z = cf.log_get_var_id("stateEstimate", "z")
    return [bytes([0x51, 6, 1, 7, z, 0]), bytes([0x51, 3, 1, period_10ms])]


def test_that_without_a_client_the_clock_never_waits():
    cf, server = _served()
    try:
        cf.debug_print("TEST", "a line nobody reads")
        cf.run_until(RUN_MS)
    finally:
        server.close()
    assert (server.stats.held_s, server.stats.waited_s, server.stats.datagrams) == (0.0, 0.0, 0)
    assert len(server.console.pending) == 1  # kept for a client to come


def test_that_a_null_probe_is_answered_without_taking_the_link(client):
    cf, server = _served()
    probe, owner = client(), client()
    try:
        owner.sendto(bytes([0xD1, 0]), server.address)  # a request (the protocol version): the client
        probe.sendto(b"\xff", server.address)
        cf.run_until(20)
        assert probe.recv(64) == b"\xf3"
        assert owner.recv(64)[:2] == b"\xd1\x00"
        assert server.client == owner.getsockname()
        probe.sendto(bytes([0xF0]) + b"echo", server.address)  # an echo is a keep-alive too
        cf.run_until(40)
        assert probe.recv(64) == b"\xf0echo" and server.client == owner.getsockname()
    finally:
        server.close()
    assert server.stats.connections == 1


def test_that_a_second_client_takes_the_downlink_and_only_a_log_reset_deletes_the_blocks(client):
    # as the firmware: one link, one set of log blocks; cflib's connect sends the reset (log port, control 5)
    cf, server = _served()
    first, second = client(), client()
    try:
        for datagram in _z_block(cf, 10):
            first.sendto(datagram, server.address)
        cf.run_until(20)
        assert len(server.log.blocks) == 1
        assert _drain(first)  # the block's data (and the answers) went to the first client
        second.sendto(bytes([0xD1, 0]), server.address)  # asks the protocol version
        cf.run_until(300)
        assert server.client == second.getsockname() and len(server.log.blocks) == 1
        to_second = _drain(second)
        assert any(datagram[0] == 0x52 for datagram in to_second)  # log data (port 5, channel 2) now go there
        assert not any(datagram[0] == 0x52 for datagram in _drain(first))
        second.sendto(bytes([0x51, 5]), server.address)  # CONTROL_RESET
        cf.run_until(320)
    finally:
        server.close()
    assert not server.log.blocks


def _drain(sock) -> list[bytes]:
    sock.setblocking(False)
    datagrams = []
    try:
        while True:
            datagrams.append(sock.recv(64))
    except BlockingIOError:
        return datagrams


def test_that_in_lockstep_log_data_waits_for_the_link_and_nothing_is_lost(client):
    cf, server = _served()
    server.budget = DownlinkBudget(rate=2000, burst=1)  # a narrow link, so the clock has to wait for it
    sock = client()
    received = []
    try:
        for datagram in _z_block(cf, 1):  # every 10 ms
            sock.sendto(datagram, server.address)
        for tick in range(100, RUN_MS + 1, 100):  # read as the client would, while the flight goes on
            cf.run_until(tick)
            received += _drain(sock)
    finally:
        server.close()
    stamps = [int.from_bytes(d[2:5], "little") for d in received if d[0] == 0x52]  # port 5, channel 2: data
    assert len(stamps) == RUN_MS // 10 - 1  # 10 .. 1990 ms
    assert all(b - a == 10 for a, b in zip(stamps, stamps[1:]))
    assert server.stats.stream_dropped == 0 and server.stats.waited_s > 0


def test_that_in_realtime_what_the_link_cannot_carry_is_dropped_and_requests_are_served_while_waiting(client):
    cf, server = _served(lockstep=False)
    server.budget = DownlinkBudget(rate=1, burst=3)
    sock = client()

    def pacer():  # the realtime pacer's wait, without the camera process
        while True:
            server.serve_for(0.001)
            yield v_task_delay(10)

    cf.x_task_create(pacer(), "PACER", 6)
    try:
        for datagram in _z_block(cf, 1):
            sock.sendto(datagram, server.address)
        cf.run_until(RUN_MS)
        cf.debug_print("TEST", "waits for the link")
        cf.run_until(RUN_MS + 20)
    finally:
        server.close()
    assert server.stats.stream_dropped > 100 and server.stats.streamed <= 4
    assert (server.stats.held_s, server.stats.waited_s) == (0.0, 0.0)
    assert len(server.console.pending) == 1, "console text is kept, not dropped"
