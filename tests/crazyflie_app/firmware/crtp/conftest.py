"""What the CRTP tests share: a flight served over CRTP in its own process, for stock cflib to connect to.

``FlightProcess(map, options)`` starts ``python -c "...serve_flight()"``: the child builds the flight (the
CRTP server bound, its URI printed), waits for the test to say ``go`` (after the test's client has sent its
first request, so the client meets the flight at its first tick), flies, and prints the summary, the server's
figures, and every 10 ms the values a log block can hold (``RECORDED``), read from the registry on the same
tick as the server samples. A flight in another process keeps the two interpreters from sharing one GIL, as a
real client and a real Crazyflie share nothing.

``slow_until_reconnect_from_ms``: from that tick on, until a new client connects, the child's flight runs no
faster than real time. A lockstep flight whose client has left runs as fast as the downlink or the CPU let it
(15 simulated seconds in about a wall second), so a test that reconnects mid-flight would otherwise race the
flight to its end.
"""
import time
import json
import os
import socket
import subprocess
import sys
import threading
from dataclasses import asdict
from pathlib import Path

import cflib.crtp
import pytest
from cflib.crazyflie import Crazyflie as CflibCrazyflie
from cflib.crazyflie.log import LogConfig
from cflib.crazyflie.syncCrazyflie import SyncCrazyflie

from tests.conftest import REPO_ROOT

RECORDED = ("stateEstimate.x", "stateEstimate.y", "stateEstimate.z", "app.phase", "app.targetId", "app.errU")
RECORD_PERIOD_MS = 10
CHILD_TIMEOUT_S = 120
SCAN_PORTS = range(19850, 19860)  # cflib's UDP scan


def serve_flight() -> None:
    """The child: argv[1] is {"map", "seed", "options", "out"} as JSON."""
    from crazyflie_app.firmware import v_task_delay
    from host_tools.flight.harness import Flight
    from host_tools.flight.registry import camera_factory
    from host_tools.maps import load_map

    config = json.loads(sys.argv[1])
    pmap = load_map(config["map"])
    flight = Flight(pmap, camera_factory("oracle")(pmap, seed=config["seed"]), seed=config["seed"],
                    out_dir=config["out"], options=config["options"])
    cf = flight.rig.cf
    record = []

    def recorder():
        while True:
            record.append([cf.x_task_get_tick_count()] + [cf.registry.log_read(name) for name in RECORDED])
            yield v_task_delay(RECORD_PERIOD_MS)

    cf.x_task_create(recorder(), "TEST_RECORDER", 0)
    slow_from_ms = config.get("slow_until_reconnect_from_ms")
    if slow_from_ms is not None and flight.crtp is not None:
        cf.x_task_create(_real_time_until_reconnect(flight.crtp, slow_from_ms), "TEST_PACER", 0)
    print(json.dumps({"uri": flight.crtp.uri if flight.crtp else None}), flush=True)
    sys.stdin.readline()
    flight.run()
    flight.close()
    summary = flight.summary()
    (Path(config["out"]) / "record.json").write_text(json.dumps(record))
    crtp = flight.crtp
    print(json.dumps({"summary": summary, "stats": asdict(crtp.stats) if crtp else None,
                      "toc_items": [crtp.log.toc_items_served, crtp.param.toc_items_served] if crtp else None,
                      "toc_sizes": [len(crtp.log.toc().entries), len(crtp.param.toc().entries)] if crtp else None}),
          flush=True)


def _real_time_until_reconnect(server, from_ms: int):
    """A task that, from ``from_ms``, sleeps a wall millisecond per simulated one until ``server`` counts a new
    connection."""
    from crazyflie_app.firmware import v_task_delay

    yield v_task_delay(from_ms)
    connections = server.stats.connections
    while server.stats.connections == connections:
        time.sleep(0.001)
        yield v_task_delay(1)


class FlightProcess:
    """A flight served over CRTP in a child process (see the module docstring)."""

    def __init__(self, out_dir: Path, map_name: str = "map1", seed: int = 0, options: dict | None = None,
                 slow_until_reconnect_from_ms: int | None = None):
        self.out_dir = Path(out_dir)
        config = {"map": map_name, "seed": seed, "out": str(self.out_dir), "options": options or {},
                  "slow_until_reconnect_from_ms": slow_until_reconnect_from_ms}
        env = dict(os.environ, PYTHONPATH=str(REPO_ROOT))
        self.process = subprocess.Popen(
            [sys.executable, "-c", "from tests.crazyflie_app.firmware.crtp.conftest import serve_flight; "
                                   "serve_flight()", json.dumps(config)],
            cwd=REPO_ROOT, env=env, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        self.uri = json.loads(self.process.stdout.readline())["uri"]
        self.result = None

    def go(self) -> None:
        self.process.stdin.write("go\n")
        self.process.stdin.flush()

    def finish(self) -> dict:
        """Wait for the flight's end -> {"summary", "stats", "toc_items", "toc_sizes"}."""
        out, _ = self.process.communicate(timeout=CHILD_TIMEOUT_S)
        assert self.process.returncode == 0, "the flight process failed"
        self.result = json.loads(out.strip().splitlines()[-1])
        return self.result

    def record(self) -> dict[int, list]:
        """tick -> the RECORDED values at that tick."""
        return {row[0]: row[1:] for row in json.loads((self.out_dir / "record.json").read_text())}

    def kill(self) -> None:
        if self.process.poll() is None:
            self.process.kill()
            self.process.communicate()


@pytest.fixture
def flight_process(tmp_path):
    """Start flights with ``flight_process(options=...)``; every child is gone after the test."""
    started = []

    def start(**kwargs) -> FlightProcess:
        child = FlightProcess(tmp_path / ("flight%d" % len(started)), **kwargs)
        started.append(child)
        return child

    yield start
    for child in started:
        child.kill()


def free_scan_port() -> int:
    """A port of cflib's scan range that nothing on this machine is bound to now."""
    for port in SCAN_PORTS:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
            try:
                probe.bind(("127.0.0.1", port))
            except OSError:
                continue
            return port
    pytest.skip("every port of cflib's scan range 19850-19859 is in use")


class Session:
    """One stock-cflib connection (SyncCrazyflie) opened in a thread, so that the test can let the flight
    start once the client's first request is on its way (``first_sent``), then ``wait()`` for it."""

    def __init__(self, uri: str, cache_dir: Path):
        cflib.crtp.init_drivers()
        self.scf = SyncCrazyflie(uri, cf=CflibCrazyflie(rw_cache=str(cache_dir)))
        self.console = []
        self.scf.cf.console.receivedChar.add_callback(self.console.append)
        self.first_sent = threading.Event()
        self.scf.cf.packet_sent.add_callback(lambda packet: self.first_sent.set())
        self._error = None
        self._thread = threading.Thread(target=self._open, daemon=True)
        self._thread.start()

    def _open(self):
        try:
            self.scf.open_link()
        except Exception as err:  # noqa: BLE001 - handed to the test thread
            self._error = err

    def wait(self, timeout_s: float = 30.0) -> "Session":
        """Until connected (TOCs loaded), then until every param value has been read."""
        self._thread.join(timeout_s)
        assert not self._thread.is_alive(), "cflib did not connect within %.0f s" % timeout_s
        if self._error is not None:
            raise self._error
        self.scf.wait_for_params()
        return self

    @property
    def cf(self) -> CflibCrazyflie:
        return self.scf.cf

    def start_block(self, name: str, period_ms: int, variables) -> list:
        """Add and start a log block; -> the list its (timestamp, {name: value}) samples are appended to."""
        samples = []
        config = LogConfig(name, period_ms)
        for variable in variables:
            config.add_variable(variable)
        self.cf.log.add_config(config)
        config.data_received_cb.add_callback(lambda ts, data, _: samples.append((ts, dict(data))))
        config.start()
        return samples

    def close(self) -> None:
        self.scf.close_link()


def wait_for(predicate, timeout_s: float = 30.0, what: str = "condition") -> None:
    """Poll ``predicate`` every 10 ms until true (a test of a live flight waits on what the client sees)."""
    event = threading.Event()
    for _ in range(int(timeout_s / 0.01)):
        if predicate():
            return
        event.wait(0.01)
    raise AssertionError("timed out waiting for %s" % what)
