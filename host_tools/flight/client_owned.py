"""Idle emulated Crazyflies that a client flies (``foranav crazyflie``), one process each, in real time.

    serve_drones(specs, out=sys.stdout) -> int       the parent: start one process per drone, wait, clean up
    python -m host_tools.flight.client_owned SPEC    one drone (SPEC: a DroneSpec as JSON)

A drone is the emulated Crazyflie (either plant) resting on the ground of a map, serving CRTP on its own UDP
port with nothing else running: no app, no camera (``Drone``); or, with ``DroneSpec.app``, with the flight
app and its camera loaded, the app waiting on ``app.start`` (``MissionDrone``). The client owns an idle
drone, as cflib owns a Crazyflie on the desk: it arms it (``cf.supervisor.send_arming_request``), streams
setpoints (``cf.commander``, the MotionCommander), reads and writes params, logs. The clock is the wall
clock (as ``--realtime``): requests are served while the pacer waits between ticks.

Drone ``i`` of ``N`` serves ``udp://HOST:PORT+i`` and starts at the map's first waypoint, ``i *
SPACING_M`` to the left (y) of it, yaw 0. Its MAVLink log (heartbeat, estimate, ground truth, console) goes
to ``OUT/droneI.tlog``. A crash (a fall faster than the plant's crash speed, a flip) is printed and logged;
the drone then lies where it fell and still answers its client.

Stopping. Ctrl-C (SIGINT to the process group), SIGTERM, the time limit, or the parent's death stop every
drone: each closes its socket and its tlog (renamed into place) and exits; the parent waits for every child
(killing one that has not gone within ``STOP_TIMEOUT_S``), so nothing is left running. A client that
vanishes leaves an idle drone (its log blocks deleted after the radio timeout, as the firmware's); a drone in
the air whose setpoints stop is handled by the firmware plant's own commander watchdog (level, then motors
off after 2 s).
"""
import json
import os
import signal
import subprocess
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TextIO

from crazyflie_app.firmware import Crazyflie, v_task_delay
from crazyflie_app.firmware.crtp.server import CrtpServer
from host_tools.errors import ForaNavError
from host_tools.flight.components import (MAV_STATE_ACTIVE, MAV_STATE_CRITICAL, MAV_STATE_EMERGENCY,
                                          MAV_STATE_STANDBY, check_crtp_endpoint, map_bounds)
from host_tools.flight.telemetry import TlogWriter
from host_tools.maps import load_map

SPACING_M = 0.5  # between two drones on the ground
PACE_PERIOD_MS = 10  # simulated ms between two wall-clock pacing points


class WallClockPacer:
    """A firmware task that holds simulated time to the wall clock: ``wait(seconds)`` spends the time it is
    ahead (serving CRTP requests meanwhile); ``max_lag_s`` is how far it ever fell behind."""

    def __init__(self, cf: Crazyflie, wait):
        self.cf = cf
        self.wait = wait
        self.max_lag_s = 0.0

    def task(self):
        wall0 = time.monotonic()
        while True:
            ahead = wall0 + self.cf.x_task_get_tick_count() / 1000.0 - time.monotonic()
            if ahead > 0:
                self.wait(ahead)
            self.max_lag_s = max(self.max_lag_s, -ahead)
            yield v_task_delay(PACE_PERIOD_MS)
TELEMETRY_PERIOD_MS = 100
HEARTBEAT_PERIOD_MS = 1000
RUN_CHUNK_MS = 100  # the loop looks at its stop conditions this often (simulated, = wall)
READY_TIMEOUT_S = 60.0
STOP_TIMEOUT_S = 5.0
MISSION_MAX_TIME_S = 24 * 3600.0  # a drone with an app: the flight's own limit (its client may wait long)
IDLE_STATES = ("PRE_FLIGHT", "PRE_FLIGHT_CHECKS_NOT_PASSED", "NOT_INITIALIZED", "LANDED", "READY_TO_FLY")


@dataclass(frozen=True)
class DroneSpec:
    """One drone of ``foranav crazyflie``: plain data, so it crosses to its process as JSON."""
    index: int
    plant: str
    host: str
    port: int
    map: str
    seed: int = 0
    out_dir: str | None = None
    max_time_s: float | None = None
    app: str | None = None  # a flight app loaded ('python', 'c'): it waits for the client's app.start = 1
    camera: str = "sim"  # the loaded app's camera ('sim', 'oracle')


class _Stop:
    """Why a drone stops: a signal, the time limit, or its parent gone."""

    def __init__(self, max_time_s: float | None):
        self.reason = None
        self.deadline = None if max_time_s is None else time.monotonic() + max_time_s
        self.parent = os.getppid()
        signal.signal(signal.SIGINT, self._signal)
        signal.signal(signal.SIGTERM, self._signal)

    def _signal(self, signum, _frame) -> None:
        self.reason = signal.Signals(signum).name

    def check(self) -> str | None:
        if self.reason is None and self.deadline is not None and time.monotonic() >= self.deadline:
            self.reason = "time limit"
        if self.reason is None and os.getppid() != self.parent:
            self.reason = "parent gone"
        return self.reason


class Drone:
    """One idle emulated Crazyflie on the ground of a map, serving CRTP in real time, logging a tlog."""

    def __init__(self, spec: DroneSpec):
        self.spec = spec
        pmap = load_map(spec.map)
        x0, y0 = pmap.waypoints[0]
        self.start = (float(x0), float(y0) + spec.index * SPACING_M, 0.0)
        self.cf = Crazyflie(seed=spec.seed + spec.index, plant=spec.plant, start=self.start,
                            bounds=map_bounds(pmap))
        try:
            self.server = CrtpServer(self.cf, spec.host, spec.port, lockstep=False)
        except OSError as err:
            self.cf.close()
            raise ForaNavError("--crtp %s:%d: cannot serve there: %s" % (spec.host, spec.port, err.strerror or err))
        self.tlog = None
        if spec.out_dir is not None:
            Path(spec.out_dir).mkdir(parents=True, exist_ok=True)
            self.tlog = TlogWriter(Path(spec.out_dir) / ("drone%d.tlog" % spec.index))
            self.cf.console.listeners.append(lambda tick, module, text: self.tlog.status_text(
                tick, "%s: %s" % (module, text)))
        self.crash_reported = False
        self.pacer = WallClockPacer(self.cf, self.server.serve_for)

    @property
    def uri(self) -> str:
        return self.server.uri

    def _monitor(self):
        """The tlog's telemetry and the crash report."""
        while True:
            now = self.cf.x_task_get_tick_count()
            model = self.cf.model
            if model.crashed and not self.crash_reported:
                self.crash_reported = True
                self.cf.debug_print("SIL", "CRASHED: %s" % model.crash_reason)
            if self.tlog is not None:
                if now % HEARTBEAT_PERIOD_MS == 0:
                    self._heartbeat(now)
                if now % TELEMETRY_PERIOD_MS == 0:
                    est, truth = model.estimate, model.truth
                    self.tlog.local_position(now, est.x, est.y, est.z, est.vx, est.vy, est.vz)
                    self.tlog.ground_truth(now, truth.x, truth.y, truth.z)
            yield v_task_delay(TELEMETRY_PERIOD_MS if now % TELEMETRY_PERIOD_MS == 0 else 1)

    def _heartbeat(self, now: int) -> None:
        state = str(self.cf.supervisor.state)
        if self.cf.model.crashed or state == "LOCKED":
            status = MAV_STATE_EMERGENCY
        elif state in ("WARNING_LEVEL_OUT", "EXCEPTION_FREE_FALL"):
            status = MAV_STATE_CRITICAL
        else:
            status = MAV_STATE_STANDBY if state in IDLE_STATES else MAV_STATE_ACTIVE
        self.tlog.heartbeat(now, 0, self.cf.supervisor_is_armed(), status)

    def run(self, stop: _Stop) -> str:
        """Serve until ``stop`` says why; -> the reason."""
        self.cf.x_task_create(self._monitor(), "DRONE_MONITOR", 0)
        self.cf.x_task_create(self.pacer.task(), "DRONE_PACER", 0)
        self.server.start()
        while stop.check() is None:
            self.cf.run_until(self.cf.x_task_get_tick_count() + RUN_CHUNK_MS)
        return stop.reason

    def close(self) -> None:
        self.server.close()
        if self.tlog is not None:
            self.tlog.close(keep=True)
        self.cf.close()


class MissionDrone:
    """A drone with the flight app loaded and its camera running (the harness's flight, on the wall clock):
    on the ground, motors off, its app waiting on ``app.start`` until the client writes 1; then it flies the
    mission as ``foranav fly`` would, and stays (landed, still serving) until stopped. Outputs of a flight
    (flight.tlog, summary.json, trajectory.png) go to OUT/droneI/."""

    def __init__(self, spec: DroneSpec):
        from host_tools.flight import harness  # the flight stack: loaded only by a drone that flies a mission

        self.spec = spec
        self.pmap = load_map(spec.map)
        x0, y0 = self.pmap.waypoints[0]
        self.start = (float(x0), float(y0) + spec.index * SPACING_M, 0.0)
        seed = spec.seed + spec.index
        try:
            self.camera = harness.camera_factory(spec.camera)(self.pmap, seed=seed)
        except ValueError as err:
            raise ForaNavError("--camera %s: %s" % (spec.camera, err))
        options = {"plant": spec.plant, "app": spec.app, "crtp": "%s:%d" % (spec.host, spec.port),
                   "lockstep": False, "start": self.start[:2], "params": {"app.start": 0},
                   "max_time_s": MISSION_MAX_TIME_S}
        out_dir = None if spec.out_dir is None else Path(spec.out_dir) / ("drone%d" % spec.index)
        try:
            self.flight = harness.Flight(self.pmap, self.camera, seed=seed, out_dir=out_dir, options=options,
                                         stop_after_landing=False)
        except BaseException:
            self._close_camera()
            raise
        self.cf = self.flight.rig.cf
        self.server = self.flight.crtp
        self.pacer = WallClockPacer(self.cf, self.flight.wait_wall)
        self.summary = None

    @property
    def uri(self) -> str:
        return self.server.uri

    def run(self, stop: _Stop) -> str:
        self.cf.x_task_create(self.pacer.task(), "DRONE_PACER", 0)
        self.flight.run(stop=lambda: stop.check() is not None)
        return stop.check() or "mission time limit"

    def report(self) -> dict:
        """What the mission did (after close): the flight summary's scoring."""
        summary = self.summary or {}
        return {key: summary.get(key) for key in ("completed", "success", "targets", "reached", "missed_targets",
                                                  "mean_deviation_m", "mission_time_s")}

    def _close_camera(self) -> None:
        close = getattr(self.camera, "close", None)
        if close is not None:
            close()

    def close(self) -> None:
        try:
            self.flight.close(keep=True)
            self.summary = self.flight.summary()
            if self.flight.out_dir is not None:
                self.flight.write_outputs(self.summary)
        finally:
            self._close_camera()


def _serve_one(spec: DroneSpec) -> int:
    """The drone's process: bind, say READY with the URI, serve until stopped, report, exit."""
    stop = _Stop(spec.max_time_s)
    try:
        drone = Drone(spec) if spec.app is None else MissionDrone(spec)
    except ForaNavError as err:
        print(json.dumps({"error": str(err)}), flush=True)
        return 2
    uri = drone.uri
    print(json.dumps({"ready": uri, "start": drone.start}), flush=True)
    try:
        reason = drone.run(stop)
    finally:
        drone.close()
    stats = drone.server.stats
    print(json.dumps({"stopped": reason, "uri": uri, "sim_s": drone.cf.x_task_get_tick_count() / 1000.0,
                      "connections": stats.connections, "crashed": drone.cf.model.crashed,
                      "crash": drone.cf.model.crash_reason, "stream_dropped": stats.stream_dropped,
                      "max_lag_s": round(drone.pacer.max_lag_s, 3),
                      "mission": drone.report() if spec.app is not None else None}), flush=True)
    return 0


def _mission_text(mission: dict | None) -> str:
    """'; mission: 6 of 6 targets reached, completed' (a drone with an app), '' otherwise."""
    if mission is None:
        return ""
    reached = {r["id"] for r in mission["reached"] or []} & set(mission["targets"] or [])
    return "; mission: %d of %d targets reached, %s, mean deviation %s m" % (
        len(reached), len(mission["targets"] or []), "completed" if mission["completed"] else "not completed",
        mission["mean_deviation_m"])


def _stop_children(children: list[subprocess.Popen]) -> None:
    for child in children:
        if child.poll() is None:
            child.send_signal(signal.SIGTERM)
    deadline = time.monotonic() + STOP_TIMEOUT_S
    for child in children:
        try:
            child.wait(max(0.0, deadline - time.monotonic()))
        except subprocess.TimeoutExpired:
            child.kill()
            child.wait()


def _interrupt(signum, frame) -> None:
    raise KeyboardInterrupt


def check_ports(specs: list[DroneSpec]) -> None:
    """ForaNavError naming the first port that cannot be served, before any drone starts."""
    for spec in specs:
        check_crtp_endpoint("%s:%d" % (spec.host, spec.port))


def serve_drones(specs: list[DroneSpec], out: TextIO = sys.stdout) -> int:
    """Start a process per drone, print each URI once it serves, wait until they stop (their time limit,
    Ctrl-C, SIGTERM), print what each did; nothing is left running. 0, or 2 if a drone could not start."""
    check_ports(specs)
    children = []
    status = 0
    previous_term = signal.signal(signal.SIGTERM, _interrupt)  # a SIGTERM to the parent stops it as Ctrl-C does
    try:
        for spec in specs:
            children.append(subprocess.Popen([sys.executable, "-m", "host_tools.flight.client_owned",
                                              json.dumps(asdict(spec))], stdout=subprocess.PIPE, text=True))
        for spec, child in zip(specs, children):
            line = child.stdout.readline()
            answer = json.loads(line) if line.strip() else {"error": "drone %d exited at start" % spec.index}
            if "error" in answer:
                raise ForaNavError(answer["error"])
            print("drone %d: %s (on the ground at x=%.2f y=%.2f)" % (spec.index, answer["ready"],
                                                                      *answer["start"][:2]), file=out, flush=True)
        for spec, child in zip(specs, children):
            for line in child.stdout:
                report = json.loads(line)
                crash = " CRASHED: %s" % report["crash"] if report["crashed"] else ""
                print("drone %d: stopped (%s) after %.1f s, %d connection(s), behind the wall clock at most "
                      "%.2f s%s%s" % (spec.index, report["stopped"], report["sim_s"], report["connections"],
                                      report["max_lag_s"], crash, _mission_text(report.get("mission"))),
                      file=out, flush=True)
            child.wait()
    except KeyboardInterrupt:
        print("stopping %d drone(s)" % len(children), file=out, flush=True)
    except ForaNavError:
        status = 2
        raise
    finally:
        _stop_children(children)
        for child in children:
            if child.stdout is not None:
                child.stdout.close()
        signal.signal(signal.SIGTERM, previous_term)
    return status


if __name__ == "__main__":
    sys.exit(_serve_one(DroneSpec(**json.loads(sys.argv[1]))))
