"""The components a flight is composed of (see ``host_tools.flight.harness``): ``FlightRig`` (emulated
Crazyflie + pty wire + the app), ``FlightRecord`` (taps: reached trees, trajectory, tlog), ``HideFault``,
``Delivery`` and ``CameraFeed`` (the lockstep world task: frames, wire faults, latency), ``Monitor``
(trajectory, telemetry, progress, stop after landing) and, with option crtp, the Crazyflie's CRTP server
(``open_crtp``: cflib and cfclient connect to the flight, docs/crtp.md)."""
import heapq
import math
import os
import socket
from collections.abc import Callable
from pathlib import Path
from typing import Protocol

import numpy as np

from crazyflie_app.firmware import Crazyflie, MavModelConfig, v_task_delay
from crazyflie_app.firmware.commander import setpoint_t
from crazyflie_app.firmware.crtp import CrtpServer
from crazyflie_app.firmware.freertos import Task
from crazyflie_app.firmware.sil.stack import FirmwarePlantConfig, FirmwarePlantUnavailable, check_available
from crazyflie_app.firmware.supervisor import LANDED, LOCKED, WARNING_LEVEL_OUT
from crazyflie_app.app.navigation_core import (PHASE_APPROACH, PHASE_DONE, PHASE_NAMES, PHASE_NO_CAMERA, PHASE_NO_DECK,
                                           rotate)
from host_tools.errors import ForaNavError
from host_tools.flight.registry import Camera, app_factory
from host_tools.flight.telemetry import TlogWriter, connect_live
from host_tools.flight.wire import PtyWire
from host_tools.maps import PlantationMap

WORLD_TASK_PRI = 6  # above the stabilizer: bytes land on the wire before the firmware looks at the tick
MONITOR_TASK_PRI = 0  # below the app: samples what the app did on this tick
MONITOR_PERIOD_MS = 10
TELEMETRY_PERIOD_MS = 100
HEARTBEAT_PERIOD_MS = 1000
TRAJECTORY_PERIOD_MS = 50
PROGRESS_PERIOD_MS = 1000  # progress callbacks (the demo's bar); cmd_fly prints at most every 5 s of wall clock
AFTER_LANDING_MS = 500  # keep running this long after the app is done
PARTIAL_SPLIT_DELAY_MS = 3
REACHED_MATCH_RADIUS_M = 0.3  # a reached point farther than this from every tree reached nothing
GARBAGE_LINES = (b"OK", b"ERR Unsupported command [foo]", b"ALIVE", b"INF Camera ready", b"T2 15",
                 b"N2 oil_palm 12 -40", b"T2 abc def", b"T2 5000 0", b"\x00\xff\xfe binary",
                 b"X" * 150, b"T2 1 2 3 4 5 6 7 8 9 " * 8)
MAV_STATE_STANDBY, MAV_STATE_ACTIVE, MAV_STATE_CRITICAL, MAV_STATE_EMERGENCY = 3, 4, 5, 6

class FlightView(Protocol):
    """What scoring (``summary``) and the plot (``plot``) read of a finished flight; ``harness.Flight`` is one.
    Declared here, below the harness, so neither of them imports the harness that imports them."""

    pmap: PlantationMap
    camera: Camera
    seed: int
    options: dict
    rig: "FlightRig"
    record: "FlightRecord"
    hide: "HideFault"
    reached: list
    trajectory: list
    detections: list
    app_trees: list


class FlightRig:
    """The bench: the emulated Crazyflie, the pty wire and the app under test, configured for one map."""

    def __init__(self, pmap: PlantationMap, camera: Camera, seed: int, options: dict):
        start = options["start"] or pmap.waypoints[0]
        model = plant_config(options["plant"], options["model"])
        decks = tuple(options["decks"])
        if options["plant"] == "firmware" and model.positioning == "flow":
            decks = tuple(d for d in decks if d != "bcLoco")  # the firmware flies what is on board
        factory = app_factory(options["app"])
        self.cf = Crazyflie(seed=seed, model_config=model, decks=decks, start=(float(start[0]), float(start[1]), 0.0),
                            plant=options["plant"], bounds=map_bounds(pmap))
        self.wire = PtyWire(lockstep=bool(options["lockstep"]))
        self.cf.attach_uart2(self.wire.slave_path)  # the camera's wire on the deck port
        try:
            self.app = factory(self.cf, pmap.waypoints, pmap.target_species)
        except BaseException:
            self.wire.close()
            self.cf.close()
            raise
        registry = self.cf.registry
        registry.param_set("app.altitude", pmap.altitude_m)
        if pmap.row_spacing_m > 0.0:  # the planting's row spacing, when the map gives it (app.rowSpacing)
            registry.param_set("app.rowSpacing", pmap.row_spacing_m)
        registry.param_set("app.camLatency", camera.latency_ms)
        for name, value in (options["params"] or {}).items():
            try:
                registry.param_set(name, value)
            except (KeyError, AssertionError, ValueError) as err:
                self.close()
                raise ForaNavError("flight option params: %s" % err)
        # the true camera mount is the camera's; the app's camOffset params are its belief about it
        self.mount = tuple(getattr(camera, "mount_offset",
                                   (self.app.params.cam_offset_x_m, self.app.params.cam_offset_y_m)))

    def now(self) -> int:
        return self.cf.x_task_get_tick_count()

    def true_pose(self) -> tuple[float, float, float, float]:
        t = self.cf.model.truth
        return (t.x, t.y, t.z, t.yaw)

    def camera_pose(self) -> tuple[float, float, float, float, float, float]:
        """The true pose the camera sees from: (x, y, z, yaw, roll, pitch), degrees, pitch in the stateEstimate
        sign. The reduced plant flies level (roll = pitch = 0: the nadir frames); the firmware plant's body
        tilts, and the rendered view tilts with it (host_tools.sim.camera.Pose)."""
        t = self.cf.model.truth
        return (t.x, t.y, t.z, t.yaw, t.roll, t.pitch)

    def camera_ground_point(self) -> tuple[float, float]:
        x, y, z, yaw = self.true_pose()
        ox, oy = rotate(yaw, *self.mount)
        return x + ox, y + oy

    def close(self) -> None:
        self.app.link.close()
        self.wire.close()
        self.cf.close()


def plant_config(plant: str, model: dict | None) -> MavModelConfig | FirmwarePlantConfig:
    """The plant's config from the flight option ``model`` (ForaNavError names a bad field, or says how to
    build the firmware plant when it is not built)."""
    if plant == "firmware":
        try:
            check_available()
        except FirmwarePlantUnavailable as err:
            raise ForaNavError("--plant firmware: %s" % err)
    config_class = FirmwarePlantConfig if plant == "firmware" else MavModelConfig
    try:
        return config_class(**(model or {})).validate()
    except (TypeError, ValueError) as err:
        raise ForaNavError("flight option model: %s" % err)


def map_bounds(pmap: PlantationMap) -> tuple[float, float, float, float]:
    """(xmin, ymin, xmax, ymax) of the waypoints and trees: the area the Loco anchors surround."""
    xs = [p[0] for p in pmap.waypoints] + [t.x for t in pmap.trees]
    ys = [p[1] for p in pmap.waypoints] + [t.y for t in pmap.trees]
    return (min(xs), min(ys), max(xs), max(ys))


def open_tlog(out_dir: str | os.PathLike | None, options: dict) -> TlogWriter | None:
    """The MAVLink log of a flight in ``out_dir`` (teed to options["mavlink"]), or None without out_dir."""
    if out_dir is None:
        return None
    live = None
    if options["mavlink"]:  # first: a refused endpoint leaves no (empty) output folder behind
        try:
            live = connect_live(options["mavlink"])
        except Exception as err:  # pymavlink raises socket, serial or OS errors for a bad URL
            raise ForaNavError("--mavlink %s: cannot open: %s" % (options["mavlink"], err))
    Path(out_dir).mkdir(parents=True, exist_ok=True)
    return TlogWriter(Path(out_dir) / "flight.tlog", live=live)


def _bind_error(endpoint: str, err: OSError) -> ForaNavError:
    return ForaNavError("--crtp %s: cannot serve there: %s" % (endpoint, err.strerror or err))


def open_crtp(cf: Crazyflie, options: dict) -> CrtpServer | None:
    """The CRTP server of option crtp ('HOST:PORT', checked by check_options), bound now so that a port in
    use is an error before the flight; None without the option."""
    if options["crtp"] is None:
        return None
    host, _, port = options["crtp"].rpartition(":")
    try:
        return CrtpServer(cf, host, int(port), lockstep=bool(options["lockstep"]))
    except OSError as err:
        raise _bind_error(options["crtp"], err)


def check_crtp_endpoint(endpoint: str) -> None:
    """ForaNavError unless 'HOST:PORT' can be served now (the commands check before they start any work)."""
    host, _, port = endpoint.rpartition(":")
    try:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
            probe.bind((host, int(port)))
    except OSError as err:
        raise _bind_error(endpoint, err)


class FlightRecord:
    """Taps on the rig's console, events and commander: what the app did, for scoring, plots and the tlog."""

    def __init__(self, pmap: PlantationMap, rig: FlightRig, tlog: TlogWriter | None = None):
        self.pmap, self.rig, self.tlog = pmap, rig, tlog
        self.reached = []  # {id, deviation_m, t_s, app_tree, point}
        self.trajectory = []  # (t_ms, true x, y, est x, y, phase)
        self.detections = []  # world points of the detections, as the app placed them
        self.app_trees = []  # (id, x, y) trees the app stored
        self.estimate_errors = []  # (horizontal position error m, yaw error deg) while airborne
        self.takeoff_ms = None
        self.done_ms = None
        self._null_reported = False
        rig.cf.console.listeners.append(self._on_console)
        rig.cf.console.event_listeners.append(self._on_event)
        rig.cf.commander.listeners.append(self._on_setpoint)

    def _on_console(self, tick: int, module: str, text: str) -> None:
        if self.tlog is not None:
            self.tlog.status_text(tick, "%s: %s" % (module, text))

    def _on_setpoint(self, sp: setpoint_t, priority: int) -> None:
        if self.tlog is None:
            return
        tick = self.rig.now()
        if sp.is_null():
            if not self._null_reported:
                self._null_reported = True
                self.tlog.status_text(tick, "null setpoint: motors off", severity=5)
            return
        self._null_reported = False
        yaw = self.rig.cf.model.estimate.yaw
        vx, vy = rotate(yaw, sp.velocity.x, sp.velocity.y) if sp.velocity_body else (sp.velocity.x, sp.velocity.y)
        self.tlog.position_target(tick, vx, vy, sp.position.z, sp.attitude.yaw)

    def _on_event(self, tick: int, name: str, payload: dict) -> None:
        if name == "detection":
            self.detections.append((payload["x"], payload["y"]))
            p = self.rig.app.params
            if self.tlog is not None:
                self.tlog.landing_target(tick, payload["tree_id"], payload["u"], payload["v"], p.cam_width_px,
                                         p.cam_height_px, p.focal_px, payload["z"])
        elif name == "tree_added":
            self.app_trees.append((payload["tree_id"], payload["x"], payload["y"]))
        elif name == "tree_reached":
            self._record_reached(tick, payload)
        elif name == "phase" and self.takeoff_ms is None and self.rig.app.phase != 0:
            self.takeoff_ms = tick

    def _record_reached(self, tick: int, payload: dict) -> None:
        gx, gy = self.rig.camera_ground_point()
        nearest = min(self.pmap.trees, key=lambda t: math.hypot(t.x - gx, t.y - gy))
        distance = math.hypot(nearest.x - gx, nearest.y - gy)
        self.reached.append({"id": nearest.id if distance <= REACHED_MATCH_RADIUS_M else None,
                             "deviation_m": round(distance, 4), "t_s": round(tick / 1000.0, 3),
                             "app_tree": payload["tree_id"], "point": (gx, gy)})

    def close(self, keep: bool = True) -> None:
        if self.tlog is not None:
            self.tlog.close(keep=keep)
            self.tlog = None


class HideFault:
    """Fault: one tree hidden from the camera for hide_s, from hide_at_s or when the app first approaches it."""

    def __init__(self, pmap: PlantationMap, rig: FlightRig, options: dict):
        self.pmap, self.rig = pmap, rig
        self.tree, self.duration_s, self.at_s = options["hide_tree"], options["hide_s"], options["hide_at_s"]
        self.started_ms = None
        self.until_ms = None

    def hidden_ids(self, now: int) -> frozenset[int]:
        if self.until_ms is not None and self.started_ms <= now < self.until_ms:
            return frozenset([self.tree])
        return frozenset()

    def update(self, now: int) -> None:
        if self.tree is None or self.started_ms is not None:
            return
        if self.at_s is not None:
            start = now >= float(self.at_s) * 1000.0
        else:
            start = False
            app = self.rig.app
            if app.phase == PHASE_APPROACH:
                tx, ty = app.target_x, app.target_y
                nearest = min(self.pmap.trees, key=lambda t: math.hypot(t.x - tx, t.y - ty))
                start = nearest.id == self.tree
        if start:
            self.started_ms = now
            self.until_ms = now + int(float(self.duration_s) * 1000)


class Delivery:
    """Bytes due on the wire at a simulated time: a heap in time order (ties: first scheduled first)."""

    def __init__(self, wire: PtyWire):
        self.wire = wire
        self._pending = []  # (deliver_ms, seq, bytes)
        self._seq = 0

    def schedule(self, deliver_ms: float, data: bytes) -> None:
        heapq.heappush(self._pending, (deliver_ms, self._seq, data))
        self._seq += 1

    def next_due_ms(self) -> float | None:
        return self._pending[0][0] if self._pending else None

    def deliver_due(self, now: int, silenced: bool = False) -> None:
        """Write (or, when ``silenced``, lose) every chunk due by ``now``."""
        while self._pending and self._pending[0][0] <= now:
            _, _, data = heapq.heappop(self._pending)
            if not silenced:
                self.wire.write(data)


class CameraFeed:
    """The lockstep world task: the camera's frames at its frame period, the wire faults, the latency."""

    def __init__(self, camera: Camera, rig: FlightRig, hide: HideFault, options: dict, seed: int):
        self.camera, self.rig, self.hide, self.options = camera, rig, hide, options
        self.rng = np.random.default_rng([seed, 0x5EED])  # harness faults, independent of camera and model
        self.delivery = Delivery(rig.wire)

    def _capture(self, now: int) -> None:
        opts = self.options
        self.hide.update(now)
        lines = [line.encode("ascii", "replace") if isinstance(line, str) else bytes(line)
                 for line in self.camera.capture(now, self.rig.camera_pose(), hidden=self.hide.hidden_ids(now))]
        if opts["dropout"] > 0:
            lines = [line for line in lines
                     if not line.startswith((b"T2", b"N2")) or self.rng.random() >= opts["dropout"]]
        if opts["garbage_rate"] > 0 and self.rng.random() < opts["garbage_rate"]:
            lines.insert(int(self.rng.integers(0, len(lines) + 1)),
                         GARBAGE_LINES[int(self.rng.integers(0, len(GARBAGE_LINES)))])
        data = b"".join(line + b"\r\n" for line in lines)
        deliver = now + self.camera.latency_ms
        if opts["partial_rate"] > 0 and len(data) > 1 and self.rng.random() < opts["partial_rate"]:
            cut = int(self.rng.integers(1, len(data)))
            self.delivery.schedule(deliver, data[:cut])
            self.delivery.schedule(deliver + PARTIAL_SPLIT_DELAY_MS, data[cut:])
        elif data:
            self.delivery.schedule(deliver, data)

    def _silenced(self, now: int) -> bool:
        return any(start * 1000.0 <= now < (start + duration) * 1000.0
                   for start, duration in self.options["silence"])

    def task(self) -> Task:
        next_capture = 0
        while True:
            now = self.rig.now()
            if now >= next_capture:
                self._capture(now)
                next_capture += self.camera.frame_period_ms
            self.delivery.deliver_due(now, silenced=self._silenced(now))
            due = self.delivery.next_due_ms()
            wake = next_capture if due is None else min(next_capture, due)
            yield v_task_delay(wake - now)


def yaw_difference(a_deg: float, b_deg: float) -> float:
    """a - b wrapped into [-180, 180)."""
    return (a_deg - b_deg + 180.0) % 360.0 - 180.0


def estimate_error(truth, estimate) -> tuple[float, float]:
    """(horizontal position error m, absolute yaw error deg) of the state estimate."""
    return (math.hypot(estimate.x - truth.x, estimate.y - truth.y), abs(yaw_difference(estimate.yaw, truth.yaw)))


class Monitor:
    """The lowest-priority harness task: samples the trajectory, writes telemetry, reports progress and
    stops the scheduler once the app is done and the MAV has landed."""

    def __init__(self, rig: FlightRig, record: FlightRecord, hide: HideFault,
                 progress: Callable[[float, str], None] | None = None, stop_after_landing: bool = True):
        self.rig, self.record, self.hide, self.progress = rig, record, hide, progress
        self.stop_after_landing = stop_after_landing  # False: a served drone stays on the ground, answering

    def task(self) -> Task:
        rig, record = self.rig, self.record
        while True:
            now = rig.now()
            truth, est = rig.cf.model.truth, rig.cf.model.estimate
            phase = rig.app.phase
            self.hide.update(now)
            if now % TRAJECTORY_PERIOD_MS == 0:
                record.trajectory.append((now, truth.x, truth.y, est.x, est.y, phase))
                if record.takeoff_ms is not None and record.done_ms is None:
                    record.estimate_errors.append(estimate_error(truth, est))
            if record.tlog is not None:
                if now % HEARTBEAT_PERIOD_MS == 0:
                    self._heartbeat(now, phase)
                if now % TELEMETRY_PERIOD_MS == 0:
                    record.tlog.local_position(now, est.x, est.y, est.z, est.vx, est.vy, est.vz)
                    record.tlog.ground_truth(now, truth.x, truth.y, truth.z)
                    record.tlog.estimate_error(now, est.x - truth.x, est.y - truth.y, yaw_difference(est.yaw, truth.yaw))
            if self.progress is not None and now % PROGRESS_PERIOD_MS == 0 and now > 0:
                self.progress(now / 1000.0, PHASE_NAMES[phase])
            state = rig.cf.supervisor.state
            crashed = rig.cf.model.crashed
            if phase in (PHASE_DONE, PHASE_NO_DECK, PHASE_NO_CAMERA) or state == LOCKED or crashed:
                if record.done_ms is None:
                    record.done_ms = now
                landed = state in (LANDED, LOCKED) or crashed or phase in (PHASE_NO_DECK, PHASE_NO_CAMERA)
                if landed and now - record.done_ms >= AFTER_LANDING_MS and self.stop_after_landing:
                    rig.cf.scheduler.stop()
            yield v_task_delay(MONITOR_PERIOD_MS)

    def _heartbeat(self, now: int, phase: int) -> None:
        state = self.rig.cf.supervisor.state
        status = {LOCKED: MAV_STATE_EMERGENCY, WARNING_LEVEL_OUT: MAV_STATE_CRITICAL}.get(
            state, MAV_STATE_ACTIVE if state not in (LANDED, "PRE_FLIGHT") else MAV_STATE_STANDBY)
        armed = state not in (LANDED, LOCKED, "PRE_FLIGHT")
        self.record.tlog.heartbeat(now, phase, armed, status)
