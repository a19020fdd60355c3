"""The flight harness: the app on the emulated Crazyflie, a camera on the other end of a real pty, faults,
telemetry, scoring. ``run_flight`` is the interface the flight commands (fly, paper-tests, replay) build on.

    run_flight(pmap, camera, *, seed=0, out_dir=None, options=None, progress=None) -> summary dict

``camera`` is any object with ``frame_period_ms``, ``latency_ms`` and
``capture(t_ms, true_pose, hidden=frozenset()) -> list[str]`` (the serial lines of one frame, without line
ends; the harness adds CRLF and delivers them ``latency_ms`` later). ``true_pose`` is the MAV's true
(x, y, z, yaw_deg); the camera applies its own mount offset (optional attribute ``mount_offset`` = (forward,
left) m, used for scoring; default: the app's camOffset params). ``hidden`` is the set of tree ids the camera
must not see at that moment (fault injection).

Simulated time only: the harness runs the firmware scheduler tick by tick, writes each frame's bytes into
the pty master at delivery time and, in lockstep mode, waits until they are readable on the slave side
before the clock moves on, so the same map and seed give the same summary and the same tlog bytes.

``options`` (all optional; unknown keys are an error):

    dropout        probability that the harness drops a detection line (after the camera's own dropout)
    hide_tree      tree id to hide from the camera ...
    hide_s         ... for this many seconds (default 5) ...
    hide_at_s      ... starting at this time, or (None) when the app first approaches that tree
    silence        [(start_s, duration_s), ...]: windows in which nothing reaches the wire
    garbage_rate   probability per frame of injecting a non-detection line (console replies, noise,
                   malformed and overlong lines, truncated detections)
    partial_rate   probability per frame that its bytes are split into two writes 3 ms apart
    lockstep       wait for the bytes to cross the pty (default True; False = no waiting, not reproducible)
    max_time_s     simulated-time limit (default 900)
    model          dict of MavModelConfig fields (estimator, noise, bias, wind_gust_mps2, ...)
    params         dict of app parameters to set before flight, by 'group.name' ('app.settleRadius': 5)
    start          (x, y) take-off point (default: the first waypoint)
    mavlink        live MAVLink output URL (e.g. 'udpout:127.0.0.1:14550'); needs out_dir (it tees the tlog)
    app            the flight app: 'python' (crazyflie_app/navigation.py, default) or 'c' (the C core of
                   crazyflie_app/bolt, crazyflie_app/c_app.py); both read the camera through the emulated UART2
    decks          decks present (default ('bcFlow2', 'bcLoco'))
    app            the flight app under test, by registered name (default 'python'; see register_app)

``progress(t_s, phase_name)`` is called every simulated second.

A flight is composed, not subclassed: ``FlightRig`` (emulated Crazyflie + pty wire + the app, built by a
registered app factory: ``register_app``), ``FlightRecord`` (taps: reached trees, trajectory, tlog),
``HideFault``, ``CameraFeed`` (the lockstep world task: frames, wire faults, latency, via ``Delivery``) and
``Monitor`` (trajectory, telemetry, progress, stop after landing), assembled by ``Flight``; ``summarize``
scores it. ``realtime`` and ``replay`` build a ``Flight`` and pass their own world task. ``fly(...)`` is the
harness as a picklable function of plain data, for sweeps.
"""
import heapq
import importlib
import math
import time
from pathlib import Path

import numpy as np

from crazyflie_app.firmware import Crazyflie, MavModelConfig, v_task_delay
from crazyflie_app.firmware.supervisor import LANDED, LOCKED, WARNING_LEVEL_OUT
from crazyflie_app.navigation import NavigationApp
from crazyflie_app.uart2_link import Uart2Link
from crazyflie_app.navigation_core import (PHASE_APPROACH, PHASE_DONE, PHASE_NAMES, PHASE_NO_CAMERA, PHASE_NO_DECK,
                                           rotate)
from host_tools import fileio
from host_tools.errors import ForaNavError
from host_tools.flight.stats import mean_ci95
from host_tools.flight.wire import PtyWire

DEFAULT_OPTIONS = {
    "dropout": 0.0, "hide_tree": None, "hide_s": 5.0, "hide_at_s": None, "silence": (), "garbage_rate": 0.0,
    "partial_rate": 0.0, "lockstep": True, "max_time_s": 900.0, "model": None, "params": None, "start": None,
    "mavlink": None, "decks": ("bcFlow2", "bcLoco"), "app": "python",
}
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

_CAMERAS = {}
# cameras that live in their own module, imported on first use; the module calls register_camera()
CAMERA_MODULES = {"sim": "host_tools.flight.vision_camera"}


def register_camera(name, factory):
    """Make ``foranav fly --camera NAME`` available: factory(pmap, seed=..., **kwargs) -> camera object."""
    _CAMERAS[name] = factory


def camera_factory(name):
    """The factory registered for ``name``, importing its module first if it has one (see CAMERA_MODULES)."""
    if name not in _CAMERAS and name in CAMERA_MODULES:
        try:
            importlib.import_module(CAMERA_MODULES[name])
        except ModuleNotFoundError as err:
            if err.name != CAMERA_MODULES[name]:
                raise
    if name not in _CAMERAS:
        if name in CAMERA_MODULES:
            raise ForaNavError("--camera %s: not available yet (needs the vision half: %s)"
                               % (name, CAMERA_MODULES[name]))
        raise ForaNavError("--camera %s: unknown camera (have %s)" % (name, ", ".join(sorted(_CAMERAS))))
    return _CAMERAS[name]


def _options(options):
    merged = dict(DEFAULT_OPTIONS)
    for key, value in (options or {}).items():
        if key not in DEFAULT_OPTIONS:
            raise ForaNavError("flight option %r: unknown (known: %s)" % (key, ", ".join(sorted(DEFAULT_OPTIONS))))
        merged[key] = value
    for key in ("dropout", "garbage_rate", "partial_rate"):
        if not 0.0 <= float(merged[key]) <= 1.0:
            raise ForaNavError("flight option %s: must be a probability in [0, 1], got %r" % (key, merged[key]))
    if float(merged["hide_s"]) < 0 or float(merged["max_time_s"]) <= 0:
        raise ForaNavError("flight options hide_s / max_time_s must be positive")
    return merged


# -- the app: a component the flight is composed with -----------------------------------------------------------

def _python_app(cf, waypoints, target_label):
    return NavigationApp(cf, waypoints, None, link=Uart2Link(cf), target_label=target_label)


def _c_app(cf, waypoints, target_label):
    from crazyflie_app.c_app import CNavigationApp  # loads (and if stale, builds) the C core's shared library
    return CNavigationApp(cf, waypoints, target_label=target_label)


_APPS = {"python": _python_app, "c": _c_app}


def register_app(name, factory):
    """Make flight option ``app=NAME`` available.

    ``factory(cf, waypoints, target_label) -> app``, ``cf`` with the camera's wire attached to its emulated
    UART2 (``cf.attach_uart2``), which the app reads as the Bolt's deck port; the app registers its PARAM/LOG tables on
    ``cf.registry`` and offers what the harness reads of the Python app: ``start()``, ``phase``,
    ``target_x``/``target_y``, ``params`` (cam_offset_x_m, cam_offset_y_m, cam_width_px, cam_height_px,
    focal_px), ``link`` (``close()``, ``lines_dropped``), ``core.counters`` (detections, out_of_column,
    recoveries, abandoned, link_losses), ``core.link_aborted``; it emits the console events ``detection``,
    ``tree_added``, ``tree_reached`` and ``phase``.
    """
    _APPS[name] = factory


def app_names():
    return sorted(_APPS)


def _app_factory(name):
    if name not in _APPS:
        raise ForaNavError("flight option app: unknown app %r (have %s)" % (name, ", ".join(app_names())))
    return _APPS[name]


# -- the components of a flight ---------------------------------------------------------------------------------

class FlightRig(object):
    """The bench: the emulated Crazyflie, the pty wire and the app under test, configured for one map."""

    def __init__(self, pmap, camera, seed, options):
        start = options["start"] or pmap.waypoints[0]
        try:
            model = MavModelConfig(**(options["model"] or {})).validate()
        except (TypeError, ValueError) as err:
            raise ForaNavError("flight option model: %s" % err)
        factory = _app_factory(options["app"])
        self.cf = Crazyflie(seed=seed, model_config=model, decks=tuple(options["decks"]),
                            start=(float(start[0]), float(start[1]), 0.0))
        self.wire = PtyWire(lockstep=bool(options["lockstep"]))
        self.cf.attach_uart2(self.wire.slave_path)  # the camera's wire on the deck port
        try:
            self.app = factory(self.cf, pmap.waypoints, pmap.target_species)
        except BaseException:
            self.wire.close()
            raise
        registry = self.cf.registry
        registry.param_set("app.altitude", pmap.altitude_m)
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

    def now(self):
        return self.cf.x_task_get_tick_count()

    def true_pose(self):
        t = self.cf.model.truth
        return (t.x, t.y, t.z, t.yaw)

    def camera_ground_point(self):
        x, y, z, yaw = self.true_pose()
        ox, oy = rotate(yaw, *self.mount)
        return x + ox, y + oy

    def close(self):
        self.app.link.close()
        self.wire.close()


def open_tlog(out_dir, options):
    """The MAVLink log of a flight in ``out_dir`` (teed to options["mavlink"]), or None without out_dir."""
    if out_dir is None:
        return None
    from host_tools.flight.telemetry import TlogWriter
    Path(out_dir).mkdir(parents=True, exist_ok=True)
    try:
        return TlogWriter(Path(out_dir) / "flight.tlog", live_url=options["mavlink"])
    except Exception as err:  # pymavlink raises socket, serial or OS errors for a bad URL
        raise ForaNavError("--mavlink %s: cannot open: %s" % (options["mavlink"], err))


class FlightRecord(object):
    """Taps on the rig's console, events and commander: what the app did, for scoring, plots and the tlog."""

    def __init__(self, pmap, rig, tlog=None):
        self.pmap, self.rig, self.tlog = pmap, rig, tlog
        self.reached = []  # {id, deviation_m, t_s, app_tree, point}
        self.trajectory = []  # (t_ms, true x, y, est x, y, phase)
        self.detections = []  # world points of the detections, as the app placed them
        self.app_trees = []  # (id, x, y) trees the app stored
        self.takeoff_ms = None
        self.done_ms = None
        self._null_reported = False
        rig.cf.console.listeners.append(self._on_console)
        rig.cf.console.event_listeners.append(self._on_event)
        rig.cf.commander.listeners.append(self._on_setpoint)

    def _on_console(self, tick, module, text):
        if self.tlog is not None:
            self.tlog.status_text(tick, "%s: %s" % (module, text))

    def _on_setpoint(self, sp, priority):
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

    def _on_event(self, tick, name, payload):
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

    def _record_reached(self, tick, payload):
        gx, gy = self.rig.camera_ground_point()
        nearest = min(self.pmap.trees, key=lambda t: math.hypot(t.x - gx, t.y - gy))
        distance = math.hypot(nearest.x - gx, nearest.y - gy)
        self.reached.append({"id": nearest.id if distance <= REACHED_MATCH_RADIUS_M else None,
                             "deviation_m": round(distance, 4), "t_s": round(tick / 1000.0, 3),
                             "app_tree": payload["tree_id"], "point": (gx, gy)})

    def close(self, keep=True):
        if self.tlog is not None:
            self.tlog.close(keep=keep)
            self.tlog = None


class HideFault(object):
    """Fault: one tree hidden from the camera for hide_s, from hide_at_s or when the app first approaches it."""

    def __init__(self, pmap, rig, options):
        self.pmap, self.rig = pmap, rig
        self.tree, self.duration_s, self.at_s = options["hide_tree"], options["hide_s"], options["hide_at_s"]
        self.started_ms = None
        self.until_ms = None

    def hidden_ids(self, now):
        if self.until_ms is not None and self.started_ms <= now < self.until_ms:
            return frozenset([self.tree])
        return frozenset()

    def update(self, now):
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


class Delivery(object):
    """Bytes due on the wire at a simulated time: a heap in time order (ties: first scheduled first)."""

    def __init__(self, wire):
        self.wire = wire
        self._pending = []  # (deliver_ms, seq, bytes)
        self._seq = 0

    def schedule(self, deliver_ms, data):
        heapq.heappush(self._pending, (deliver_ms, self._seq, data))
        self._seq += 1

    def next_due_ms(self):
        return self._pending[0][0] if self._pending else None

    def deliver_due(self, now, silenced=False):
        """Write (or, when ``silenced``, lose) every chunk due by ``now``."""
        while self._pending and self._pending[0][0] <= now:
            _, _, data = heapq.heappop(self._pending)
            if not silenced:
                self.wire.write(data)


class CameraFeed(object):
    """The lockstep world task: the camera's frames at its frame period, the wire faults, the latency."""

    def __init__(self, camera, rig, hide, options, seed):
        self.camera, self.rig, self.hide, self.options = camera, rig, hide, options
        self.rng = np.random.default_rng([seed, 0x5EED])  # harness faults, independent of camera and model
        self.delivery = Delivery(rig.wire)

    def _capture(self, now):
        opts = self.options
        self.hide.update(now)
        lines = [line.encode("ascii", "replace") if isinstance(line, str) else bytes(line)
                 for line in self.camera.capture(now, self.rig.true_pose(), hidden=self.hide.hidden_ids(now))]
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

    def _silenced(self, now):
        return any(start * 1000.0 <= now < (start + duration) * 1000.0
                   for start, duration in self.options["silence"])

    def task(self):
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


class Monitor(object):
    """The lowest-priority harness task: samples the trajectory, writes telemetry, reports progress and
    stops the scheduler once the app is done and the MAV has landed."""

    def __init__(self, rig, record, hide, progress=None):
        self.rig, self.record, self.hide, self.progress = rig, record, hide, progress

    def task(self):
        rig, record = self.rig, self.record
        while True:
            now = rig.now()
            truth, est = rig.cf.model.truth, rig.cf.model.estimate
            phase = rig.app.phase
            self.hide.update(now)
            if now % TRAJECTORY_PERIOD_MS == 0:
                record.trajectory.append((now, truth.x, truth.y, est.x, est.y, phase))
            if record.tlog is not None:
                if now % HEARTBEAT_PERIOD_MS == 0:
                    self._heartbeat(now, phase)
                if now % TELEMETRY_PERIOD_MS == 0:
                    record.tlog.local_position(now, est.x, est.y, est.z, est.vx, est.vy, est.vz)
                    record.tlog.ground_truth(now, truth.x, truth.y, truth.z)
            if self.progress is not None and now % PROGRESS_PERIOD_MS == 0 and now > 0:
                self.progress(now / 1000.0, PHASE_NAMES[phase])
            state = rig.cf.supervisor.state
            if phase in (PHASE_DONE, PHASE_NO_DECK, PHASE_NO_CAMERA) or state == LOCKED:
                if record.done_ms is None:
                    record.done_ms = now
                landed = state in (LANDED, LOCKED) or phase in (PHASE_NO_DECK, PHASE_NO_CAMERA)
                if landed and now - record.done_ms >= AFTER_LANDING_MS:
                    rig.cf.scheduler.stop()
            yield v_task_delay(MONITOR_PERIOD_MS)

    def _heartbeat(self, now, phase):
        state = self.rig.cf.supervisor.state
        status = {LOCKED: MAV_STATE_EMERGENCY, WARNING_LEVEL_OUT: MAV_STATE_CRITICAL}.get(
            state, MAV_STATE_ACTIVE if state not in (LANDED, "PRE_FLIGHT") else MAV_STATE_STANDBY)
        armed = state not in (LANDED, LOCKED, "PRE_FLIGHT")
        self.record.tlog.heartbeat(now, phase, armed, status)


class Flight(object):
    """One flight, composed: rig + record (+ tlog) + hide fault + monitor; the world task is pluggable.

    ``world_task`` (a generator run at WORLD_TASK_PRI) defaults to the camera feed (CameraFeed); realtime
    and replay pass their own (wall-clock pose feed, clip playback). Everything a flight owns lives here, so
    nothing is left behind once it is closed.
    """

    def __init__(self, pmap, camera, *, seed=0, out_dir=None, options=None, progress=None):
        self.options = _options(options)
        self.pmap, self.camera, self.seed, self.progress = pmap, camera, seed, progress
        self.out_dir = Path(out_dir) if out_dir is not None else None
        self.rig = FlightRig(pmap, camera, seed, self.options)
        try:
            tlog = open_tlog(self.out_dir, self.options)
        except BaseException:
            self.rig.close()
            raise
        self.record = FlightRecord(pmap, self.rig, tlog)
        self.hide = HideFault(pmap, self.rig, self.options)
        self.feed = CameraFeed(camera, self.rig, self.hide, self.options, seed)
        self.monitor = Monitor(self.rig, self.record, self.hide, progress)
        self.camera_killed_ms = None  # set by realtime's --kill-camera-at (the plot marks it)
        self.cpu_s = 0.0

    # what the plot and the summary read
    reached = property(lambda self: self.record.reached)
    trajectory = property(lambda self: self.record.trajectory)
    detections = property(lambda self: self.record.detections)
    app_trees = property(lambda self: self.record.app_trees)

    def run(self, world_task=None):
        cf = self.rig.cf
        cf.x_task_create(world_task if world_task is not None else self.feed.task(), "HARNESS_CAMERA",
                         WORLD_TASK_PRI)
        self.rig.app.start()
        cf.x_task_create(self.monitor.task(), "HARNESS_MONITOR", MONITOR_TASK_PRI)
        cpu0 = time.process_time()
        cf.run_until(int(float(self.options["max_time_s"]) * 1000) + 1)
        self.cpu_s = time.process_time() - cpu0

    def close(self, keep=True):
        self.rig.close()
        self.record.close(keep=keep)

    def summary(self):
        return summarize(self)

    def write_outputs(self, summary):
        """flight.tlog is already there; add trajectory.png, summary.json (and the camera's detections.csv)."""
        from host_tools.flight.plot import plot_trajectory
        summary["tlog"] = str(self.out_dir / "flight.tlog")
        summary["plot"] = str(self.out_dir / "trajectory.png")
        summary["summary"] = str(self.out_dir / "summary.json")
        plot_trajectory(self, summary["plot"])
        if hasattr(self.camera, "frames_csv"):
            summary["detections_csv"] = str(self.out_dir / "detections.csv")
            fileio.write_text(summary["detections_csv"], self.camera.frames_csv())
        fileio.write_json(summary["summary"], {k: v for k, v in summary.items() if k != "cpu_s"})


def summarize(flight):
    """The flight summary (the record fly prints and sweeps store) of a finished Flight."""
    rig, record, pmap = flight.rig, flight.record, flight.pmap
    targets = sorted(t.id for t in pmap.targets)
    target_set = set(targets)
    visits = [r["id"] for r in record.reached]
    non_targets = [i for i in visits if i is not None and i not in target_set]
    deviations = [r["deviation_m"] for r in record.reached if r["id"] in target_set]
    mean, ci95 = mean_ci95(deviations)
    supervisor, app = rig.cf.supervisor, rig.app
    watchdog = [{"t_s": t / 1000.0, "state": s} for t, s in supervisor.watchdog_events]
    # a landing forced by a dead camera link is safe, but the mission was not completed
    completed = app.phase == PHASE_DONE and supervisor.state != LOCKED and not app.core.link_aborted
    counts = {i: visits.count(i) for i in targets}
    success = (completed and all(c == 1 for c in counts.values()) and not non_targets
               and None not in visits and not watchdog)
    end_ms = record.done_ms if record.done_ms is not None else rig.now()
    counters = app.core.counters
    return {
        "map": Path(pmap.source).stem if pmap.source else pmap.name,
        "seed": flight.seed,
        "completed": completed,
        "success": success,
        "targets": targets,
        "reached": [{"id": r["id"], "deviation_m": r["deviation_m"], "t_s": r["t_s"]} for r in record.reached],
        "missed_targets": [i for i in targets if counts[i] == 0],
        "repeated_targets": [i for i in targets if counts[i] > 1],
        "non_targets_visited": non_targets,
        "spurious_reached": sum(1 for i in visits if i is None),
        "mean_deviation_m": None if mean is None else round(mean, 4),
        "ci95_m": None if ci95 is None else round(ci95, 4),
        "max_deviation_m": max(deviations) if deviations else None,
        "mission_time_s": round((end_ms - (record.takeoff_ms or 0)) / 1000.0, 2),
        "recoveries": counters.recoveries,
        "abandoned": counters.abandoned,
        "watchdog_events": len(watchdog),
        "watchdog": watchdog,
        "detections": counters.detections,
        "out_of_column_detections": counters.out_of_column,
        "serial_lines_dropped": app.link.lines_dropped,
        "link_losses": counters.link_losses,
        "link_aborted": app.core.link_aborted,
        "camera_never_heard": app.phase == PHASE_NO_CAMERA,  # did not take off: not completed
        "hidden_tree": flight.options["hide_tree"],
        "hidden_from_s": None if flight.hide.started_ms is None else flight.hide.started_ms / 1000.0,
    }


def run_flight(pmap, camera, *, seed=0, out_dir=None, options=None, progress=None):
    """Fly ``pmap`` with the app against ``camera``; return the summary dict (see module docstring).

    With ``out_dir``, writes flight.tlog, trajectory.png and summary.json there and adds their paths.
    """
    flight = Flight(pmap, camera, seed=seed, out_dir=out_dir, options=options, progress=progress)
    try:
        flight.run()
    except BaseException:
        flight.close(keep=False)
        raise
    flight.close(keep=True)
    summary = flight.summary()
    if hasattr(camera, "report"):  # a camera that scores its own detections (vision_camera): per-frame figures
        summary["vision"] = camera.report()
    summary["cpu_s"] = round(flight.cpu_s, 2)  # not part of the reproducible record
    if flight.out_dir is not None:
        flight.write_outputs(summary)
    return summary


def fly(map_data, *, camera="oracle", camera_kwargs=None, app="python", options=None, seed=0):
    """The harness as a function: (map, camera, app, options, seed) -> summary, from plain data only.

    ``map_data`` is a map JSON object (host_tools.maps), ``camera`` a registered camera name built with
    ``camera_kwargs``, ``app`` a registered app name. Picklable (a Dask task ships it by reference and its
    arguments by value); every object of the flight is built here and dropped on return, so a worker can
    fly thousands in a row. Same arguments, same summary (apart from ``cpu_s``).
    """
    from host_tools.maps import map_from_dict

    pmap = map_from_dict(map_data, source=map_data.get("name", "<map>"))
    try:
        cam = camera_factory(camera)(pmap, seed=seed, **(camera_kwargs or {}))
    except ValueError as err:
        raise ForaNavError("camera: %s" % err)
    merged = dict(options or {})
    merged["app"] = app
    try:
        return run_flight(pmap, cam, seed=seed, options=merged)
    finally:
        close = getattr(cam, "close", None)
        if close is not None:
            close()
