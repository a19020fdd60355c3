"""Replay a recorded clip through both halves, open loop: the clip's frames go through the unchanged JeVois
module and over a real pty into the app, whose state estimate follows the clip's recorded poses.

    replay_clip(clip, pmap=None, *, latency_ms=None, seed=0) -> report dict

The app runs on the emulated firmware as in flight, but the MAV model is replaced by the recording: the
truth and the state estimate are the clip's pose, interpolated at each tick, whatever the app commands.
Before the first frame the MAV hovers at the first recorded pose until the app has taken off and started
to follow the path F; then the clip plays in real (simulated) time, frame i at its ``t_s``, and the module's
lines reach the app ``latency_ms`` later (default one frame of the clip).

The report: per-frame detections against the sidecar's ground truth (when it has one), the tree map the app
built (world positions against the map's trees), and the setpoints the app sent (what it would have flown).
Real footage works the same way when the sidecar has a pose log; ``trees`` null there means no per-frame
truth, and the path F comes from the sidecar's map or ``pmap``.
"""
import bisect
import math

from crazyflie_app.firmware import v_task_delay
from crazyflie_app.app.navigation_core import PHASE_FOLLOW_PATH, PHASE_NAMES, rotate
from host_tools.errors import ForaNavError
from host_tools.flight import harness
from host_tools.flight.vision_camera import DetectionScore, parse_detections, truth_in_frame
from host_tools.jevois_host import ModuleRunner, NullLog
from host_tools.maps import PlantationMap, map_from_dict
from host_tools.sim.clip import Clip

POLL_MS = 10
END_MARGIN_MS = 500  # run this long after the last frame's lines arrived
TREE_MATCH_RADIUS_M = 0.3  # an app tree farther than this from every map tree matches none
SETPOINT_SAMPLE_MS = 100


class _PlaybackModel:
    """Stands in for the MAV model: truth and estimate are the recorded pose at the playback time."""

    crashed = False
    crash_reason = None

    def __init__(self, model, frames, clock):
        self.truth, self.estimate = model.truth, model.estimate  # the objects the log/param tables point at
        self.config = model.config
        self.distance_flown_m = 0.0
        self._times = [f.t_s for f in frames]
        self._poses = [f.pose for f in frames]
        self._clock = clock  # () -> playback time in seconds (before the first frame: 0)
        self.pose_at(0.0)

    def pose_at(self, t_s):
        i = bisect.bisect_right(self._times, t_s)
        if i <= 0 or i >= len(self._times):
            p = self._poses[0 if i <= 0 else -1]
            x, y, z, yaw, vx, vy = p.x, p.y, p.z, p.yaw_deg, 0.0, 0.0
        else:
            t0, t1, a, b = self._times[i - 1], self._times[i], self._poses[i - 1], self._poses[i]
            w = (t_s - t0) / (t1 - t0) if t1 > t0 else 0.0
            x, y, z = a.x + w * (b.x - a.x), a.y + w * (b.y - a.y), a.z + w * (b.z - a.z)
            yaw = a.yaw_deg + w * ((b.yaw_deg - a.yaw_deg + 180.0) % 360.0 - 180.0)
            dt = t1 - t0 if t1 > t0 else 1.0
            vx, vy = (b.x - a.x) / dt, (b.y - a.y) / dt
        for state in (self.truth, self.estimate):
            state.x, state.y, state.z, state.yaw, state.vx, state.vy, state.vz = x, y, z, yaw, vx, vy, 0.0

    def step(self, dt, sp, motors_on):
        self.pose_at(self._clock())


class _ClipPlayer:
    """The replay's world task and taps: plays the clip's frames through the module into the flight's wire,
    drives the MAV model from the recorded poses and samples the setpoints the app sends."""

    def __init__(self, flight, clip):
        self.flight, self.clip = flight, clip
        self.rig = flight.rig
        self.clip_t0_ms = None
        self.rig.cf.replace_model(_PlaybackModel(self.rig.cf.model, clip.frames, self.playback_s))
        self.delivery = harness.Delivery(self.rig.wire)
        self.score = DetectionScore()
        self.frame_rows = []  # per frame: index, t_s, detections (world), truth counts
        self.setpoints = []  # (t_ms, phase, world vx, vy, z)
        self._last_setpoint_ms = None
        self.rig.cf.commander.listeners.append(self._record_setpoint)

    def playback_s(self):
        return 0.0 if self.clip_t0_ms is None else (self.rig.now() - self.clip_t0_ms) / 1000.0

    def _record_setpoint(self, sp, priority):
        now = self.rig.now()
        if self.clip_t0_ms is None or sp.is_null():
            return
        if self._last_setpoint_ms is not None and now - self._last_setpoint_ms < SETPOINT_SAMPLE_MS:
            return
        self._last_setpoint_ms = now
        yaw = self.rig.cf.model.estimate.yaw
        vx, vy = rotate(yaw, sp.velocity.x, sp.velocity.y) if sp.velocity_body else (sp.velocity.x, sp.velocity.y)
        self.setpoints.append((now - self.clip_t0_ms, self.rig.app.phase, vx, vy, sp.position.z))

    def task(self):
        rig, camera = self.rig, self.flight.camera
        while rig.app.phase < PHASE_FOLLOW_PATH:
            yield v_task_delay(POLL_MS)
        self.clip_t0_ms = rig.now()
        width, height = self.clip.camera.width, self.clip.camera.height
        target_species = self.flight.pmap.target_species
        for frame, image in zip(self.clip.frames, self.clip.images()):
            due = self.clip_t0_ms + int(round(frame.t_s * 1000))
            while rig.now() < due:
                yield v_task_delay(due - rig.now())
            self.delivery.deliver_due(rig.now())
            lines = camera.runner.process_frame(image)
            pixels = parse_detections(lines, width, height)
            if frame.trees is not None:
                self.score.add(due, pixels, truth_in_frame(frame.trees, target_species))
            self.frame_rows.append({"index": frame.index, "t_s": frame.t_s, "detections": len(pixels),
                                    "truth": None if frame.trees is None else len(
                                        truth_in_frame(frame.trees, target_species))})
            data = b"".join(line.encode("ascii", "replace") + b"\r\n" for line in lines)
            self.delivery.schedule(due + camera.latency_ms, data)
        end = rig.now() + camera.latency_ms + END_MARGIN_MS
        while rig.now() < end:
            self.delivery.deliver_due(rig.now())
            yield v_task_delay(POLL_MS)
        rig.cf.scheduler.stop()
        yield v_task_delay(POLL_MS)


class _ClipCamera:
    """The module runner and the timing of the replay (the harness reads frame period and latency)."""

    def __init__(self, clip, pmap, latency_ms, module_params=None):
        self.frame_period_ms = int(round(1000.0 / clip.fps))
        self.latency_ms = self.frame_period_ms if latency_ms is None else int(latency_ms)
        params = {"species": pmap.target_species}
        params.update(module_params or {})
        self.runner = ModuleRunner(params=params, log_stream=NullLog())


def map_override_warning(clip: Clip, pmap: PlantationMap) -> str | None:
    """Pure: a one-line warning when ``pmap`` (given by the user) is not the map the clip was recorded over:
    other trees, path or height (a name change alone does not count). None when they agree or the clip has no
    map."""
    if clip.map is None:
        return None
    recorded = map_from_dict(clip.map, source=str(clip.directory / "clip.json"))
    differ = [what for what, a, b in (("trees", recorded.trees, pmap.trees),
                                      ("path", recorded.waypoints, pmap.waypoints),
                                      ("altitude_m", recorded.altitude_m, pmap.altitude_m)) if a != b]
    if not differ:
        return None
    return ("%s: map: the clip was recorded over %r, --map gives %r with other %s: its frames and poses are of "
            "the recorded map; the path F and the app's tree map are judged against --map"
            % (clip.directory / "clip.json", recorded.name, pmap.name, " and ".join(differ)))


def replay_clip(clip: Clip, pmap: PlantationMap | None = None, *, latency_ms: int | None = None, seed: int = 0,
                params: dict | None = None, app: str = "python") -> dict:
    """Play ``clip`` (host_tools.sim.clip.Clip) through the module and the app -> the report dict."""
    if pmap is None:
        if clip.map is None:
            raise ForaNavError("%s: the clip has no map; give one with --map (the path F comes from it)"
                               % clip.directory)
        pmap = map_from_dict(clip.map, source=str(clip.directory / "clip.json"))
    if not clip.frames:
        raise ForaNavError("%s: the clip has no frames" % clip.directory)
    if latency_ms is not None and latency_ms < 0:
        raise ForaNavError("--latency-ms: must not be negative")
    first = clip.frames[0].pose
    last_s = clip.frames[-1].t_s
    # the clip starts once the app follows the path, so the app must not wait for the camera before take-off
    options = {"start": (first.x, first.y), "max_time_s": last_s + 60.0,
               "params": {"app.camWaitMs": 0, **(params or {})}, "app": app}
    camera = _ClipCamera(clip, pmap, latency_ms)
    flight = harness.Flight(pmap, camera, seed=seed, options=options)
    player = _ClipPlayer(flight, clip)
    flight.rig.app.params.altitude_m = first.z  # the app flies at the recorded height
    try:
        flight.run(player.task())
    finally:
        flight.close(keep=False)
    if player.clip_t0_ms is None:
        raise ForaNavError("replay: the app never started to follow the path (phase %s)"
                           % PHASE_NAMES[flight.rig.app.phase])
    return _report(flight, player, pmap, clip)


def _report(flight, player, pmap, clip):
    app = flight.rig.app
    memory = app.core.memory
    stored = [(t.id, t.x, t.y) for t in _stored_trees(memory)]
    trees = []
    for tree_id, x, y in stored:
        nearest = min(pmap.trees, key=lambda t: math.hypot(t.x - x, t.y - y))
        error = math.hypot(nearest.x - x, nearest.y - y)
        match = nearest if error <= TREE_MATCH_RADIUS_M else None
        trees.append({"app_id": tree_id, "x": round(x, 4), "y": round(y, 4),
                      "map_id": match.id if match else None, "species": match.species if match else None,
                      "error_m": round(error, 4) if match else None})
    errors = [t["error_m"] for t in trees if t["error_m"] is not None]
    seen = _trees_seen_whole(clip, pmap.target_species)
    mapped = {t["map_id"] for t in trees if t["map_id"] is not None}
    return {
        "clip": str(clip.directory),
        "map": pmap.name,
        "frames": len(player.frame_rows),
        "duration_s": clip.frames[-1].t_s,
        "latency_ms": flight.camera.latency_ms,
        "detection": player.score.report() if player.score.frames else None,
        "per_frame": player.frame_rows,
        "tree_map": trees,
        "tree_map_mean_error_m": round(sum(errors) / len(errors), 4) if errors else None,
        "tree_map_max_error_m": round(max(errors), 4) if errors else None,
        "trees_seen_whole": sorted(seen),
        "trees_seen_not_mapped": sorted(seen - mapped),
        "spurious_app_trees": sum(1 for t in trees if t["map_id"] is None),
        "app_detections": app.core.counters.detections,
        "app_out_of_column": app.core.counters.out_of_column,
        "setpoints": [{"t_s": round(t / 1000.0, 2), "phase": PHASE_NAMES[p], "vx": round(vx, 3), "vy": round(vy, 3),
                       "z": round(z, 3)} for t, p, vx, vy, z in player.setpoints],
        "phases": _phase_durations(player.setpoints),
        "serial_bytes": flight.rig.wire.bytes_written,
    }


def _stored_trees(memory):
    """Every tree the app stored: still in memory or already visited (the visited list keeps positions)."""
    stored = {t.id: t for t in memory.visited}
    stored.update(memory.trees)
    return [stored[i] for i in sorted(stored)]


def _trees_seen_whole(clip, species):
    """Ids of the trees of ``species`` seen completely in at least one frame of the clip."""
    ids = set()
    for frame in clip.frames:
        for tree in frame.trees or ():
            if tree.complete and tree.species == species:
                ids.add(tree.id)
    return ids


def _phase_durations(setpoints):
    """Seconds spent in each phase while the clip played (from the sampled setpoints)."""
    out = {}
    for (t0, phase, *_), (t1, *_rest) in zip(setpoints, setpoints[1:]):
        out[PHASE_NAMES[phase]] = round(out.get(PHASE_NAMES[phase], 0.0) + (t1 - t0) / 1000.0, 2)
    return out


def expectation_record(report: dict) -> dict:
    """The figures of a replay report that CI pins (tests/fixtures/replay_expectations/<clip>.json)."""
    det = report["detection"] or {}
    return {
        "frames": report["frames"],
        "true_positives": det.get("true_positives"),
        "false_positives": det.get("false_positives"),
        "missed": det.get("missed"),
        "recall": det.get("recall"),
        "precision": det.get("precision"),
        "mapped_tree_ids": sorted(t["map_id"] for t in report["tree_map"] if t["map_id"] is not None),
        "tree_map_max_error_m": report["tree_map_max_error_m"],
        "spurious_app_trees": report["spurious_app_trees"],
        "setpoints": len(report["setpoints"]),
    }
