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

``progress(t_s, phase_name)`` is called every simulated second.
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


def _python_app(cf, path, target_label):
    from crazyflie_app.uart2_link import Uart2Link
    return NavigationApp(cf, path, None, link=Uart2Link(cf), target_label=target_label)


def _c_app(cf, path, target_label):
    from crazyflie_app.c_app import CNavigationApp
    return CNavigationApp(cf, path, target_label=target_label)


# the app seam: factory(cf with UART2 attached, waypoints, target species) -> the app
APPS = {"python": _python_app, "c": _c_app}


def _options(options):
    merged = dict(DEFAULT_OPTIONS)
    for key, value in (options or {}).items():
        if key not in DEFAULT_OPTIONS:
            raise ForaNavError("flight option %r: unknown (known: %s)" % (key, ", ".join(sorted(DEFAULT_OPTIONS))))
        merged[key] = value
    for key in ("dropout", "garbage_rate", "partial_rate"):
        if not 0.0 <= float(merged[key]) <= 1.0:
            raise ForaNavError("flight option %s: must be a probability in [0, 1], got %r" % (key, merged[key]))
    if merged["app"] not in APPS:
        raise ForaNavError("flight option app: %r unknown (have %s)" % (merged["app"], ", ".join(sorted(APPS))))
    if float(merged["hide_s"]) < 0 or float(merged["max_time_s"]) <= 0:
        raise ForaNavError("flight options hide_s / max_time_s must be positive")
    return merged


class _Flight(object):
    """One run: builds the pieces, owns the harness tasks, collects the record."""

    def __init__(self, pmap, camera, seed, out_dir, options, progress):
        self.pmap, self.camera, self.seed, self.options, self.progress = pmap, camera, seed, options, progress
        self.out_dir = Path(out_dir) if out_dir is not None else None
        self.rng = np.random.default_rng([seed, 0x5EED])  # harness faults, independent of camera and model
        start = options["start"] or pmap.waypoints[0]
        try:
            model = MavModelConfig(**(options["model"] or {})).validate()
        except (TypeError, ValueError) as err:
            raise ForaNavError("flight option model: %s" % err)
        self.cf = Crazyflie(seed=seed, model_config=model, decks=tuple(options["decks"]),
                            start=(float(start[0]), float(start[1]), 0.0))
        self.wire = PtyWire(lockstep=bool(options["lockstep"]))
        self.cf.attach_uart2(self.wire.slave_path)  # the camera's wire on the deck port
        self.app = APPS[options["app"]](self.cf, pmap.waypoints, pmap.target_species)
        registry = self.cf.registry
        registry.param_set("app.altitude", pmap.altitude_m)
        registry.param_set("app.camLatency", camera.latency_ms)
        self.tlog = None
        for name, value in (options["params"] or {}).items():
            try:
                registry.param_set(name, value)
            except (KeyError, AssertionError, ValueError) as err:
                self.close(keep=False)
                raise ForaNavError("flight option params: %s" % err)
        # the true camera mount is the camera's; the app's camOffset params are its belief about it
        self.mount = tuple(getattr(camera, "mount_offset",
                                   (self.app.params.cam_offset_x_m, self.app.params.cam_offset_y_m)))
        if self.out_dir is not None:
            from host_tools.flight.telemetry import TlogWriter
            self.out_dir.mkdir(parents=True, exist_ok=True)
            try:
                self.tlog = TlogWriter(self.out_dir / "flight.tlog", live_url=options["mavlink"])
            except Exception as err:  # pymavlink raises socket, serial or OS errors for a bad URL
                self.close(keep=False)
                raise ForaNavError("--mavlink %s: cannot open: %s" % (options["mavlink"], err))
        self.reached = []  # {id, deviation_m, t_s, est, truth}
        self.trajectory = []  # (t_ms, true x, y, est x, y, phase)
        self.detections = []  # world points of the detections, as the app placed them
        self.app_trees = []  # (id, x, y) trees the app stored
        self.hidden_until = None
        self.hide_started_ms = None
        self.done_ms = None
        self.takeoff_ms = None
        self._pending = []  # heap of (deliver_ms, seq, bytes)
        self._seq = 0
        self._null_reported = False
        self.cf.console.listeners.append(self._on_console)
        self.cf.console.event_listeners.append(self._on_event)
        self.cf.commander.listeners.append(self._on_setpoint)

    # -- taps -------------------------------------------------------------------------------------------------

    def _now(self):
        return self.cf.x_task_get_tick_count()

    def true_pose(self):
        t = self.cf.model.truth
        return (t.x, t.y, t.z, t.yaw)

    def camera_ground_point(self):
        x, y, z, yaw = self.true_pose()
        ox, oy = rotate(yaw, *self.mount)
        return x + ox, y + oy

    def _on_console(self, tick, module, text):
        if self.tlog is not None:
            self.tlog.status_text(tick, "%s: %s" % (module, text))

    def _on_setpoint(self, sp, priority):
        if self.tlog is None:
            return
        tick = self._now()
        if sp.is_null():
            if not self._null_reported:
                self._null_reported = True
                self.tlog.status_text(tick, "null setpoint: motors off", severity=5)
            return
        self._null_reported = False
        yaw = self.cf.model.estimate.yaw
        vx, vy = rotate(yaw, sp.velocity.x, sp.velocity.y) if sp.velocity_body else (sp.velocity.x, sp.velocity.y)
        self.tlog.position_target(tick, vx, vy, sp.position.z, sp.attitude.yaw)

    def _on_event(self, tick, name, payload):
        if name == "detection":
            self.detections.append((payload["x"], payload["y"]))
            p = self.app.params
            if self.tlog is not None:
                self.tlog.landing_target(tick, payload["tree_id"], payload["u"], payload["v"], p.cam_width_px,
                                         p.cam_height_px, p.focal_px, payload["z"])
        elif name == "tree_added":
            self.app_trees.append((payload["tree_id"], payload["x"], payload["y"]))
        elif name == "tree_reached":
            self._record_reached(tick, payload)
        elif name == "phase" and self.takeoff_ms is None and self.app.phase != 0:
            self.takeoff_ms = tick

    def _record_reached(self, tick, payload):
        gx, gy = self.camera_ground_point()
        nearest = min(self.pmap.trees, key=lambda t: math.hypot(t.x - gx, t.y - gy))
        distance = math.hypot(nearest.x - gx, nearest.y - gy)
        self.reached.append({"id": nearest.id if distance <= REACHED_MATCH_RADIUS_M else None,
                             "deviation_m": round(distance, 4), "t_s": round(tick / 1000.0, 3),
                             "app_tree": payload["tree_id"], "point": (gx, gy)})

    # -- harness tasks -----------------------------------------------------------------------------------------

    def hidden_ids(self, now):
        if self.hidden_until is not None and self.hide_started_ms <= now < self.hidden_until:
            return frozenset([self.options["hide_tree"]])
        return frozenset()

    def _maybe_start_hiding(self, now):
        opts = self.options
        if opts["hide_tree"] is None or self.hide_started_ms is not None:
            return
        if opts["hide_at_s"] is not None:
            start = now >= float(opts["hide_at_s"]) * 1000.0
        else:
            start = False
            if self.app.phase == PHASE_APPROACH:
                tx, ty = self.app.target_x, self.app.target_y
                nearest = min(self.pmap.trees, key=lambda t: math.hypot(t.x - tx, t.y - ty))
                start = nearest.id == opts["hide_tree"]
        if start:
            self.hide_started_ms = now
            self.hidden_until = now + int(float(opts["hide_s"]) * 1000)

    def _schedule(self, deliver_ms, data):
        heapq.heappush(self._pending, (deliver_ms, self._seq, data))
        self._seq += 1

    def _capture(self, now):
        opts = self.options
        self._maybe_start_hiding(now)
        lines = [line.encode("ascii", "replace") if isinstance(line, str) else bytes(line)
                 for line in self.camera.capture(now, self.true_pose(), hidden=self.hidden_ids(now))]
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
            self._schedule(deliver, data[:cut])
            self._schedule(deliver + PARTIAL_SPLIT_DELAY_MS, data[cut:])
        elif data:
            self._schedule(deliver, data)

    def _silenced(self, now):
        return any(start * 1000.0 <= now < (start + duration) * 1000.0
                   for start, duration in self.options["silence"])

    def world_task(self):
        next_capture = 0
        while True:
            now = self._now()
            if now >= next_capture:
                self._capture(now)
                next_capture += self.camera.frame_period_ms
            while self._pending and self._pending[0][0] <= now:
                _, _, data = heapq.heappop(self._pending)
                if not self._silenced(now):
                    self.wire.write(data)
            wake = next_capture if not self._pending else min(next_capture, self._pending[0][0])
            yield v_task_delay(wake - now)

    def monitor_task(self):
        while True:
            now = self._now()
            truth, est = self.cf.model.truth, self.cf.model.estimate
            phase = self.app.phase
            self._maybe_start_hiding(now)
            if now % TRAJECTORY_PERIOD_MS == 0:
                self.trajectory.append((now, truth.x, truth.y, est.x, est.y, phase))
            if self.tlog is not None:
                if now % HEARTBEAT_PERIOD_MS == 0:
                    self._heartbeat(now, phase)
                if now % TELEMETRY_PERIOD_MS == 0:
                    self.tlog.local_position(now, est.x, est.y, est.z, est.vx, est.vy, est.vz)
                    self.tlog.ground_truth(now, truth.x, truth.y, truth.z)
            if self.progress is not None and now % PROGRESS_PERIOD_MS == 0 and now > 0:
                self.progress(now / 1000.0, PHASE_NAMES[phase])
            state = self.cf.supervisor.state
            if phase in (PHASE_DONE, PHASE_NO_DECK, PHASE_NO_CAMERA) or state == LOCKED:
                if self.done_ms is None:
                    self.done_ms = now
                landed = state in (LANDED, LOCKED) or phase in (PHASE_NO_DECK, PHASE_NO_CAMERA)
                if landed and now - self.done_ms >= AFTER_LANDING_MS:
                    self.cf.scheduler.stop()
            yield v_task_delay(MONITOR_PERIOD_MS)

    def _heartbeat(self, now, phase):
        state = self.cf.supervisor.state
        status = {LOCKED: MAV_STATE_EMERGENCY, WARNING_LEVEL_OUT: MAV_STATE_CRITICAL}.get(
            state, MAV_STATE_ACTIVE if state not in (LANDED, "PRE_FLIGHT") else MAV_STATE_STANDBY)
        armed = state not in (LANDED, LOCKED, "PRE_FLIGHT")
        self.tlog.heartbeat(now, phase, armed, status)

    # -- run ---------------------------------------------------------------------------------------------------

    def run(self):
        self.cf.x_task_create(self.world_task(), "HARNESS_CAMERA", WORLD_TASK_PRI)
        self.app.start()
        self.cf.x_task_create(self.monitor_task(), "HARNESS_MONITOR", MONITOR_TASK_PRI)
        cpu0 = time.process_time()
        self.cf.run_until(int(float(self.options["max_time_s"]) * 1000) + 1)
        self.cpu_s = time.process_time() - cpu0

    def close(self, keep=True):
        self.app.link.close()
        self.wire.close()
        if self.tlog is not None:
            self.tlog.close(keep=keep)
            self.tlog = None

    def summary(self):
        targets = sorted(t.id for t in self.pmap.targets)
        target_set = set(targets)
        visits = [r["id"] for r in self.reached]
        non_targets = [i for i in visits if i is not None and i not in target_set]
        deviations = [r["deviation_m"] for r in self.reached if r["id"] in target_set]
        mean, ci95 = mean_ci95(deviations)
        watchdog = [{"t_s": t / 1000.0, "state": s} for t, s in self.cf.supervisor.watchdog_events]
        # a landing forced by a dead camera link is safe, but the mission was not completed
        completed = (self.app.phase == PHASE_DONE and self.cf.supervisor.state != LOCKED
                     and not self.app.core.link_aborted)
        counts = {i: visits.count(i) for i in targets}
        success = (completed and all(c == 1 for c in counts.values()) and not non_targets
                   and None not in visits and not watchdog)
        end_ms = self.done_ms if self.done_ms is not None else self._now()
        counters = self.app.core.counters
        return {
            "map": Path(self.pmap.source).stem if self.pmap.source else self.pmap.name,
            "seed": self.seed,
            "completed": completed,
            "success": success,
            "targets": targets,
            "reached": [{"id": r["id"], "deviation_m": r["deviation_m"], "t_s": r["t_s"]} for r in self.reached],
            "missed_targets": [i for i in targets if counts[i] == 0],
            "repeated_targets": [i for i in targets if counts[i] > 1],
            "non_targets_visited": non_targets,
            "spurious_reached": sum(1 for i in visits if i is None),
            "mean_deviation_m": None if mean is None else round(mean, 4),
            "ci95_m": None if ci95 is None else round(ci95, 4),
            "max_deviation_m": max(deviations) if deviations else None,
            "mission_time_s": round((end_ms - (self.takeoff_ms or 0)) / 1000.0, 2),
            "recoveries": counters.recoveries,
            "abandoned": counters.abandoned,
            "watchdog_events": len(watchdog),
            "watchdog": watchdog,
            "detections": counters.detections,
            "out_of_column_detections": counters.out_of_column,
            "serial_lines_dropped": self.app.link.lines_dropped,
            "link_losses": counters.link_losses,
            "link_aborted": self.app.core.link_aborted,
            "camera_never_heard": self.app.phase == PHASE_NO_CAMERA,  # did not take off: not completed
            "hidden_tree": self.options["hide_tree"],
            "hidden_from_s": None if self.hide_started_ms is None else self.hide_started_ms / 1000.0,
        }


def run_flight(pmap, camera, *, seed=0, out_dir=None, options=None, progress=None):
    """Fly ``pmap`` with the app against ``camera``; return the summary dict (see module docstring).

    With ``out_dir``, writes flight.tlog, trajectory.png and summary.json there and adds their paths.
    """
    opts = _options(options)
    flight = _Flight(pmap, camera, seed, out_dir, opts, progress)
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
        from host_tools.flight.plot import plot_trajectory
        summary["tlog"] = str(flight.out_dir / "flight.tlog")
        summary["plot"] = str(flight.out_dir / "trajectory.png")
        summary["summary"] = str(flight.out_dir / "summary.json")
        plot_trajectory(flight, summary["plot"])
        if hasattr(camera, "frames_csv"):
            summary["detections_csv"] = str(flight.out_dir / "detections.csv")
            fileio.write_text(summary["detections_csv"], camera.frames_csv())
        record = {k: v for k, v in summary.items() if k != "cpu_s"}
        fileio.write_json(summary["summary"], record)
    return summary
