"""`foranav crazyflie`: idle drones that stock cflib owns (arming, setpoints, logs), one process each, real time;
Ctrl-C and the time limit leave nothing running; a tlog per drone; bad input is one line."""
import os
import signal
import socket
import subprocess
import sys
import threading
import time

import cflib.crtp
import pytest
from cflib.crazyflie import Crazyflie as CflibCrazyflie
from cflib.crazyflie.log import LogConfig
from cflib.crazyflie.syncCrazyflie import SyncCrazyflie
from pymavlink import mavutil

from tests.conftest import REPO_ROOT
from tests.crazyflie_app.firmware.sil.conftest import needs_firmware_plant

HOVER_Z_M = 0.4
CONNECT_TIMEOUT_S = 30.0
STARTUP_TIMEOUT_S = 60.0  # two interpreters importing the flight stack on a loaded 2-core machine


def _free_ports(count: int) -> int:
    """A first port with ``count`` free UDP ports after it (above cflib's scan range, so no test meets
    another's drones)."""
    for first in range(20500, 21500, 10):
        if all(_port_free(first + i) for i in range(count)):
            return first
    raise AssertionError("no free UDP ports")


def _port_free(port: int) -> bool:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        try:
            probe.bind(("127.0.0.1", port))
        except OSError:
            return False
        return True


class Served:
    """``foranav crazyflie`` in its own session (so a Ctrl-C reaches its whole process group, as in a
    terminal)."""

    def __init__(self, tmp_path, *args):
        self.out = tmp_path / "out"
        self.process = subprocess.Popen([sys.executable, "-m", "host_tools.cli", "crazyflie", "--out", str(self.out),
                                         *args], cwd=REPO_ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                        text=True, start_new_session=True,
                                        env=dict(os.environ, PYTHONPATH=str(REPO_ROOT)))
        self.lines = []

    def wait_ready(self, count: int) -> list[str]:
        uris = []
        deadline = time.monotonic() + STARTUP_TIMEOUT_S
        while len(uris) < count and time.monotonic() < deadline:
            line = self.process.stdout.readline()
            if not line:
                break
            self.lines.append(line)
            if " udp://" in line:
                uris.append(line.split()[2])
        assert len(uris) == count, "drones did not start: %s %s" % (self.lines, self.process.stderr.read())
        return uris

    def finish(self, timeout_s: float = 30.0) -> int:
        out, err = self.process.communicate(timeout=timeout_s)
        self.lines += out.splitlines()
        self.stderr = err
        return self.process.returncode

    def kill(self) -> None:
        if self.process.poll() is None:
            os.killpg(self.process.pid, signal.SIGKILL)
            self.process.communicate()


def _hover(uri: str, cache, heights: list) -> None:
    """What cflib's MotionCommander does: arm, stream hover setpoints (zDistance), land, cut the motors;
    ``heights`` gets stateEstimate.z every 100 ms."""
    with SyncCrazyflie(uri, cf=CflibCrazyflie(rw_cache=str(cache))) as scf:
        cf = scf.cf
        block = LogConfig("z", 100)
        block.add_variable("stateEstimate.z", "float")
        cf.log.add_config(block)
        block.data_received_cb.add_callback(lambda ts, data, _: heights.append(data["stateEstimate.z"]))
        block.start()
        cf.supervisor.send_arming_request(True)
        time.sleep(0.5)
        for step in range(40):  # 2 s up to HOVER_Z_M
            cf.commander.send_hover_setpoint(0, 0, 0, min(HOVER_Z_M, 0.1 + step * 0.02))
            time.sleep(0.05)
        for step in range(30):  # 1.5 s down, then the motors cut a few cm up
            cf.commander.send_hover_setpoint(0, 0, 0, max(0.05, HOVER_Z_M - step * 0.015))
            time.sleep(0.05)
        cf.commander.send_stop_setpoint()
        cf.commander.send_notify_setpoint_stop()
        time.sleep(0.3)
        block.stop()


@pytest.mark.parametrize("plant", ["reduced", pytest.param("firmware", marks=needs_firmware_plant)])
def test_that_cflib_flies_two_drones_and_the_time_limit_leaves_nothing_running(tmp_path, plant):
    # Fixture: two drones, each its own process, stopping by themselves after 14 s
    first = _free_ports(2)
    served = Served(tmp_path, "--plant", plant, "--count", "2", "--crtp", "127.0.0.1:%d" % first,
                    "--max-time-s", "14")
    try:
        uris = served.wait_ready(2)
        # Test: stock cflib flies both at once, as a swarm script would
        cflib.crtp.init_drivers()
        heights = ([], [])
        pilots = [threading.Thread(target=_hover, args=(uri, tmp_path / ("cache%d" % i), heights[i]))
                  for i, uri in enumerate(uris)]
        for pilot in pilots:
            pilot.start()
        for pilot in pilots:
            pilot.join(CONNECT_TIMEOUT_S)
        returncode = served.finish()
    finally:
        served.kill()
    # Assert: the URIs are PORT and PORT+1; each drone climbed to the hover height and landed, none crashed
    assert uris == ["udp://127.0.0.1:%d" % first, "udp://127.0.0.1:%d" % (first + 1)]
    for samples in heights:
        assert max(samples) == pytest.approx(HOVER_Z_M, abs=0.1)
        assert samples[-1] < 0.1
    assert returncode == 0
    stopped = [line for line in served.lines if "stopped (time limit)" in line]
    assert len(stopped) == 2 and not any("CRASHED" in line for line in served.lines)
    # every drone process is gone: its port is free again; a tlog per drone, with its flight in it
    assert _port_free(first) and _port_free(first + 1)
    for index in (0, 1):
        log = mavutil.mavlink_connection(str(served.out / ("drone%d.tlog" % index)), dialect="common")
        heights_logged = []
        while (message := log.recv_match(type="DEBUG_VECT")) is not None:
            heights_logged.append(-message.z)
        assert max(heights_logged) > HOVER_Z_M - 0.1


def test_that_ctrl_c_stops_every_drone(tmp_path):
    # Fixture: three idle drones (reduced plant), no time limit
    first = _free_ports(3)
    served = Served(tmp_path, "--plant", "reduced", "--count", "3", "--crtp", "127.0.0.1:%d" % first)
    try:
        served.wait_ready(3)
        # Test: Ctrl-C in the terminal (SIGINT to the process group)
        os.killpg(served.process.pid, signal.SIGINT)
        returncode = served.finish()
    finally:
        served.kill()
    # Assert: a clean exit, every port free, every tlog in place (no .part left)
    assert returncode == 0
    assert all(_port_free(first + i) for i in range(3))
    assert sorted(p.name for p in served.out.iterdir()) == ["drone0.tlog", "drone1.tlog", "drone2.tlog"]


def test_that_a_port_in_use_is_one_line_before_any_drone_starts(tmp_path):
    first = _free_ports(2)
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as taken:
        taken.bind(("127.0.0.1", first + 1))
        served = Served(tmp_path, "--plant", "reduced", "--count", "2", "--crtp", "127.0.0.1:%d" % first)
        returncode = served.finish()
    assert returncode == 2
    assert served.stderr.strip().count("\n") == 0 and "127.0.0.1:%d" % (first + 1) in served.stderr
    assert not served.out.exists()
