"""Stock cflib against a running flight: connect, TOCs and their cache, log blocks, console, scan, param write,
disconnect and reconnect mid-flight; and (-m slow) a --realtime flight.

One scripted flight (``watched``) serves every observing test: a first session connects with an empty TOC
cache, streams a 10 ms block (the estimate) and a 100 ms block (the estimate and app variables), scans for
the URI, disconnects at 15 s of flight time; a second session reconnects at once (its TOCs from the cache),
streams the 10 ms block again and leaves at 30 s. The flight is map 1 with the oracle camera, lockstep,
cut at 40 s; its tlog is compared with the same flight flown without any server.
"""
import math
import socket
import struct
import threading

import cflib.crtp
import pytest
from pymavlink import mavutil

from host_tools.flight.harness import Flight
from host_tools.flight.realtime import run_realtime
from host_tools.flight.registry import camera_factory, check_options
from host_tools.flight.components import FlightRig
from host_tools.maps import load_map
from tests.crazyflie_app.firmware.crtp.conftest import RECORDED, FlightProcess, Session, free_scan_port, wait_for
from tests.crazyflie_app.firmware.sil.conftest import needs_firmware_plant

MAX_TIME_S = 40.0
FIRST_LEAVES_MS = 15000
SECOND_LEAVES_MS = 30000
FAST_MS, SLOW_MS = 10, 100
POSITION = ("stateEstimate.x", "stateEstimate.y", "stateEstimate.z")
APP_VARIABLES = ("app.phase", "app.targetId", "app.errU")
TLOG_PERIOD_MS = 100
ALTITUDE_WRITTEN_M = 0.9
ALTITUDE_TOLERANCE_M = 0.05
REALTIME_SPEED = 8.0  # as tests/host_tools/flight/test_realtime.py: the camera process keeps up
REALTIME_FLIGHT_S = 30.0
CONNECTED_BY_MS = 1000


def _float32(value: float) -> float:
    return struct.unpack("<f", struct.pack("<f", value))[0]


def _same(sample: float, recorded: float) -> bool:
    """A log value equals the flight's value sent as float32 (NaN included: app.errU with no target)."""
    expected = _float32(recorded) if isinstance(recorded, float) else recorded
    return (math.isnan(sample) and math.isnan(expected)) if isinstance(sample, float) and math.isnan(sample) \
        else sample == expected


def _toc_snapshot(cf) -> dict:
    """{port name: {'group.name': (id, ctype, access)}} of a connected cflib Crazyflie (cflib forgets its
    param TOC on disconnect)."""
    log, param = cf.log.toc.toc, cf.param.toc.toc
    return {"log": {"%s.%s" % (g, n): (e.ident, e.ctype) for g in log for n, e in log[g].items()},
            "param": {"%s.%s" % (g, n): (e.ident, e.ctype, e.get_readable_access()) for g in param
                      for n, e in param[g].items()}}


@pytest.fixture(scope="module")
def watched(tmp_path_factory):
    """The scripted flight of the module docstring -> what the client saw and what the flight did."""
    tmp = tmp_path_factory.mktemp("watched")
    port = free_scan_port()
    child = FlightProcess(tmp / "flight", options={"crtp": "127.0.0.1:%d" % port, "max_time_s": MAX_TIME_S},
                          slow_until_reconnect_from_ms=FIRST_LEAVES_MS)
    try:
        first = Session(child.uri, tmp / "toc_cache")
        assert first.first_sent.wait(10), "cflib sent nothing"
        child.go()
        first.wait()
        tocs = _toc_snapshot(first.cf)
        fast1 = first.start_block("fast", FAST_MS, POSITION)
        slow = first.start_block("slow", SLOW_MS, POSITION + APP_VARIABLES)
        scanned = cflib.crtp.scan_interfaces()
        wait_for(lambda: fast1 and fast1[-1][0] >= FIRST_LEAVES_MS, what="15 s of flight")
        first.close()
        second = Session(child.uri, tmp / "toc_cache").wait()
        fast2 = second.start_block("fast", FAST_MS, POSITION)
        wait_for(lambda: fast2 and fast2[-1][0] >= SECOND_LEAVES_MS, what="30 s of flight")
        second.close()
        result = child.finish()
    finally:
        child.kill()
    pmap = load_map("map1")
    reference = Flight(pmap, camera_factory("oracle")(pmap, seed=0), seed=0, out_dir=tmp / "reference",
                       options={"max_time_s": MAX_TIME_S})
    reference.run()
    reference.close()
    tlog_path = tmp / "flight" / "flight.tlog"
    return {"child": child, "result": result, "tocs": tocs, "record": child.record(), "uri": child.uri,
            "scanned": scanned, "sessions": (first, second), "fast": (fast1, fast2), "slow": slow,
            "tlog": tlog_path.read_bytes(), "tlog_path": tlog_path,
            "reference_tlog": (tmp / "reference" / "flight.tlog").read_bytes()}


def test_that_the_tocs_cflib_loads_are_the_registry_of_the_flight(watched):
    # Fixture: the registry of the same flight, built here
    pmap = load_map("map1")
    rig = FlightRig(pmap, camera_factory("oracle")(pmap, seed=0), 0, check_options({}))
    try:
        registry = rig.cf.registry
        log_types = [(name, registry.log_get_type(var_id)) for var_id, name in enumerate(registry.log_names())]
        param_entries = registry.param_entries()
    finally:
        rig.close()
    tocs = watched["tocs"]
    # Assert: every variable, with its id and type
    assert tocs["log"] == {name: (var_id, rig_type) for var_id, (name, rig_type) in enumerate(log_types)}
    assert {name: (ident, ctype) for name, (ident, ctype, _) in tocs["param"].items()} == {
        name: (index, entry.type) for index, (name, entry) in enumerate(param_entries)}
    assert tocs["param"]["deck.bcFlow2"][2] == "RO"
    assert tocs["param"]["app.altitude"][2] == "RW"


def test_that_the_second_connection_takes_its_tocs_from_the_cache(watched):
    result = watched["result"]
    # Assert: each TOC item was served once, to the first session
    assert result["toc_items"] == result["toc_sizes"]
    second = watched["sessions"][1]
    assert second.cf.log.toc.get_element_id("stateEstimate.z") == watched["sessions"][0].cf.log.toc.get_element_id(
        "stateEstimate.z")


def test_that_log_blocks_stream_every_period_without_a_gap(watched):
    for samples, period in ((watched["fast"][0], FAST_MS), (watched["fast"][1], FAST_MS), (watched["slow"], SLOW_MS)):
        stamps = [ts for ts, _ in samples]
        assert len(stamps) > 100
        assert all(b - a == period for a, b in zip(stamps, stamps[1:])), "a sample lost or late"


def test_that_logged_values_are_the_flights_values_at_their_tick(watched):
    record = watched["record"]
    samples = [(ts, data) for block in watched["fast"] + (watched["slow"],) for ts, data in block]
    assert samples
    for ts, data in samples:
        assert ts in record, "a sample at a tick the flight did not reach"
        for name, value in data.items():
            assert _same(value, record[ts][RECORDED.index(name)]), (ts, name, value, record[ts])
    heights = [data["stateEstimate.z"] for _, data in watched["fast"][0]]
    assert max(heights) > 1.0, "the climb is in the stream"


def test_that_logged_positions_are_the_tlogs(watched):
    log = mavutil.mavlink_connection(str(watched["tlog_path"]), dialect="common")
    tlog = {}
    while True:
        message = log.recv_match(type="LOCAL_POSITION_NED")
        if message is None:
            break
        tlog[message.time_boot_ms] = (message.x, -message.y, -message.z)
    compared = 0
    for ts, data in watched["fast"][0] + watched["fast"][1]:
        if ts % TLOG_PERIOD_MS == 0:
            assert tuple(data[name] for name in POSITION) == tlog[ts]
            compared += 1
    assert compared > 100


def test_that_a_console_line_arrives(watched):
    text = "".join(watched["sessions"][0].console)
    assert "FORANAV: Armed\n" in text
    assert "FORANAV: phase TAKEOFF\n" in text


def test_that_a_scan_finds_the_uri(watched):
    assert watched["uri"] in [uri for uri, _ in watched["scanned"]]


def test_that_disconnect_and_reconnect_mid_flight_lose_nothing(watched):
    # the flight went on exactly as without a client: same tlog bytes (the reconnection saw nothing missing:
    # its stream has no gap, test_that_log_blocks_stream_every_period_without_a_gap)
    assert watched["tlog"] == watched["reference_tlog"]
    result = watched["result"]
    assert result["stats"]["connections"] == 2
    assert result["stats"]["malformed"] == 0
    second_start = watched["fast"][1][0][0]
    assert FIRST_LEAVES_MS < second_start < SECOND_LEAVES_MS


@pytest.mark.parametrize("plant", [
    "reduced", pytest.param("firmware", marks=needs_firmware_plant)])
def test_that_a_param_write_changes_the_flight(flight_process, tmp_path, plant):
    child = flight_process(options={"crtp": "127.0.0.1:0", "max_time_s": 25.0, "plant": plant})
    session = Session(child.uri, tmp_path / "toc_cache")
    assert session.first_sent.wait(10)
    child.go()
    session.wait()
    written = []
    session.cf.param.add_update_callback(group="app", name="altitude", cb=lambda name, value: written.append(value))
    session.cf.param.set_value("app.altitude", ALTITUDE_WRITTEN_M)
    wait_for(lambda: written, what="the write's echo")
    session.close()
    child.finish()
    record = child.record()
    # Assert: the echo carries the new value, and the MAV climbed to it instead of the map's 1.25 m
    assert float(written[-1]) == pytest.approx(ALTITUDE_WRITTEN_M)
    cruise_heights = [values[RECORDED.index("stateEstimate.z")] for tick, values in record.items() if tick >= 20000]
    assert cruise_heights
    assert all(abs(z - ALTITUDE_WRITTEN_M) < ALTITUDE_TOLERANCE_M for z in cruise_heights)


def _port_free(port: int) -> bool:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        try:
            probe.bind(("127.0.0.1", port))
        except OSError:
            return False
        return True


@pytest.mark.slow
def test_that_stock_cflib_watches_a_realtime_flight(tmp_path):
    # Fixture: a --realtime flight (camera process, wall clock) serving CRTP, flown in a thread
    port = free_scan_port()
    result = {}
    flight = threading.Thread(target=lambda: result.update(run_realtime(
        load_map("map1"), speed=REALTIME_SPEED,
        options={"max_time_s": REALTIME_FLIGHT_S, "crtp": "127.0.0.1:%d" % port})))
    flight.start()
    wait_for(lambda: not _port_free(port), timeout_s=60, what="the server's socket")
    session = Session("udp://127.0.0.1:%d" % port, tmp_path / "toc_cache").wait(timeout_s=120)
    heights = session.start_block("z", SLOW_MS, ("stateEstimate.z",))
    wait_for(lambda: heights and max(data["stateEstimate.z"] for _, data in heights) > 1.0, timeout_s=60,
             what="the climb")
    session.close()
    flight.join(120)
    # Assert: a sample every 100 ms of flight time, and the flight went on to its time limit
    stamps = [ts for ts, _ in heights]
    assert all(b - a == SLOW_MS for a, b in zip(stamps, stamps[1:]))
    assert result["realtime"]["speed"] == REALTIME_SPEED and not result["completed"]


def test_that_the_clock_holds_while_cflib_connects(watched):
    # the first session's ~150 requests (TOCs, every param, two blocks) took well under a second of flight time:
    # without the hold, each round trip would let the oracle flight run on by ~10 ms or more
    assert watched["fast"][0][0][0] < CONNECTED_BY_MS
    assert watched["result"]["stats"]["held_s"] > 0
