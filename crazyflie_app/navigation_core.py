"""The pure core of the navigation app: Algorithm 1 as a state machine that takes time and measurements as
arguments and returns setpoints and decisions. No clock, serial port, log or commander access here.

Phases (``custom_mode`` in the telemetry heartbeat)::

    BOOT -> TAKEOFF -> FOLLOW_PATH <-> APPROACH <-> RECOVERY
                          ^   |            |            | (timeout: tree abandoned)
                          |   v            v reached    v
                          RETURN_TO_PATH <------------- +
    FOLLOW_PATH (last waypoint) -> [RECOVERY -> APPROACH: go back once per tree abandoned unseen] -> LAND -> DONE
    (null setpoints, motors off);  NO_DECK: no Flow deck, aborted;  NO_CAMERA: camera never heard, never took off

* FOLLOW_PATH flies the path F (waypoints) at ``cruiseSpeed`` with a carrot ``lookahead`` ahead of the
  MAV's projection on the current segment, which also pulls it back onto the line. A waypoint is passed
  within ``wpTolerance`` of it or once the MAV is past the end of its segment (a gust must not make it
  circle back for a 3 cm ball).
* A tree enters T_d when seen inside the planting column of the *current* segment (orthogonal distance
  <= ``columnFactor`` x ``crownSize``); after ``minHits`` detections the nearest such tree becomes the target t*.
* APPROACH: a constant-velocity Kalman filter tracks the target's image position, predicted every tick with
  the tick's real duration; detections (corrected for the MAV's motion since capture) update it. The
  visual-servo law commands a body velocity proportional to the metric image offset (``servoGain``),
  saturated at ``approachSpeed``; an integral term (``servoKi``) acts only when a disturbance holds the MAV
  near but off the centre (inside 3 settle radii and slower than ``settleSpeed``), so calm approaches stay
  monotonic. ``captureRadius`` (tau = 40 px, the paper's threshold) marks the tree as captured; the
  paper's rule alone would stop ~0.15 m off centre, so the tree is declared *reached* only once the
  filtered offset stays below ``settleRadius`` with the MAV slower than ``settleSpeed`` for ``settleDwell``
  (default 6 px ~ 2.3 cm at 1.25 m, 0.02 m/s, held 0.6 s), which keeps the mean deviation at a few mm
  with an ideal camera. So that wind cannot stall the mission, after ``settleGrace`` (8 s) captured both
  thresholds grow by ``settleRelax`` (1 px/s) up to tau: the deviation degrades gracefully instead.
* RECOVERY (insect view memory): when the MAV is farther than ``recoveryDistance`` (delta) from the stored
  s_t, or the target has not been seen for ``lostTimeoutMs``, the MAV re-approaches s_t by position until a
  detection associates with the target again, then visual guidance resumes; after ``recoveryTimeoutMs`` the
  tree is abandoned (it goes to the visited list, flagged not reached) so the mission goes on.
* Camera link watch: once the camera has sent an end-of-frame mark, a link silent for ``linkHoldMs`` while
  flying makes the MAV hold position (zero velocity at the flight height) until frames come back, when the
  mission resumes where it was; silent for ``linkLandMs`` it lands (LAND, then DONE with ``link_aborted``).
  A camera that sends no frame marks cannot be told from one that sees nothing, so it is not watched.
* After a tree, RETURN_TO_PATH flies back to the current segment until the cross-track error is below
  ``returnTolerance``.
* Going back once: a tree abandoned because recovery timed out without seeing it again (it was hidden) is
  flagged in the visited list. At the last waypoint, before landing, the app goes back to each flagged
  tree in turn (nearest first): the entry is restored into T_d as the target and approached by memory
  (RECOVERY, whose timeouts start only once the MAV is within ``returnTolerance`` of s_t), then visually.
  Reached or abandoned again, it is never flagged again; when no flagged tree is left, LAND.
* One frame, one detection per crown: detections of one frame closer than ``dupRadius`` on the ground are
  merged first (``merge_duplicates``); without this, two detector windows on one big crown (1.0 m
  altitude) became two stored trees and the tree was reached twice.
"""
import math
from collections import deque, namedtuple
from dataclasses import dataclass

from crazyflie_app.pixel_kalman import PixelKalmanFilter
from crazyflie_app.tree_memory import TreeMemory

PHASE_BOOT, PHASE_TAKEOFF, PHASE_FOLLOW_PATH, PHASE_APPROACH, PHASE_RECOVERY, PHASE_RETURN_TO_PATH, \
    PHASE_LAND, PHASE_DONE, PHASE_NO_DECK, PHASE_NO_CAMERA = range(10)
PHASE_NAMES = ("BOOT", "TAKEOFF", "FOLLOW_PATH", "APPROACH", "RECOVERY", "RETURN_TO_PATH", "LAND", "DONE",
               "NO_DECK", "NO_CAMERA")

POSE_HISTORY_LENGTH = 128  # ticks of pose history kept for latency compensation (~1.3 s at 100 Hz)

Pose = namedtuple("Pose", "x y z yaw_deg vx vy")  # the estimate: m, m, m, deg, m/s, m/s
Command = namedtuple("Command", "kind vx vy z")  # kind "hover" (body vx, vy in m/s; z abs in m) or "null"
Detection = namedtuple("Detection", "u v")  # image position, px


@dataclass
class NavigationParams:
    """Every threshold and speed law; the app exports each as a PARAM (``app.<name>``, units in the table)."""
    altitude_m: float = 1.25  # paper flight tests
    takeoff_tolerance_m: float = 0.05  # height error that counts as "at altitude"
    takeoff_settle_ms: int = 1000  # held that long before the path starts
    land_height_m: float = 0.5  # Navigation.c lands in two 3 s steps: 0.5 m ...
    land_final_m: float = 0.15  # ... then 0.15 m, then motors off
    land_step_ms: int = 3000
    arrival_min_speed: float = 0.02  # the follow law never crawls slower than this towards a waypoint
    cruise_speed: float = 0.10  # paper: <= 0.1 m/s
    waypoint_tolerance_m: float = 0.03  # Navigation.c is_at_target_mainroad
    lookahead_m: float = 0.15
    approach_speed: float = 0.10
    servo_gain: float = 0.8  # 1/s: body velocity per metre of image offset
    capture_radius_px: float = 40.0  # tau (paper / Navigation.c)
    settle_radius_px: float = 6.0
    settle_dwell_ms: int = 600
    settle_speed: float = 0.02
    settle_relax: float = 1.0  # px/s: after settle_grace_ms captured, the settle radius (and speed) grow,
    settle_grace_ms: int = 8000  # so gusts cannot keep the MAV from ever finishing a tree (cap: tau)
    servo_integral: float = 0.3  # 1/s^2: integral action of the servo law (rejects steady drift and wind)
    servo_integral_band: float = 3.0  # settle radii: the servo integrates the offset only inside this band
    recovery_distance_m: float = 0.7  # delta (Navigation.c 0.7 m switch)
    # 1.5 s = 13 frames at the paper's 9 fps. With the module in the loop, a tree right under the camera is
    # found in only ~60 % of frames for some trees (Map 3 Tree 5), in runs of misses; at 600 ms the app fell
    # into recovery again and again and never settled. The filter rides through the gaps meanwhile.
    lost_timeout_ms: int = 1500
    recovery_timeout_ms: int = 15000
    target_timeout_ms: int = 60000  # a target not reached this long after selection is abandoned: no endless
    #                                 approach/recovery cycles on a flickering detection, the mission goes on
    recovery_speed: float = 0.10
    return_tolerance_m: float = 0.05
    merge_radius_m: float = 0.45  # Navigation.c same-tree distance
    # two detections of ONE frame this close are one crown seen twice (at 1.0 m a 0.38 m crown spans 120 px
    # and the module reported two windows 0.15 m apart on it: the app stored two trees and reached one twice);
    # distinct trees stand at least a crown (crownSize 0.35 m) apart, clusters 0.35-0.47 m. Duplicates seen
    # 0.05-0.18 m apart; a cluster pair 0.47 m apart with 0.1 m edge errors on each still stays 0.27 m apart
    duplicate_radius_m: float = 0.25
    crown_size_m: float = 0.35
    column_factor: float = 1.5  # paper: 1.5 x crown size
    min_hits: int = 2
    tree_capacity: int = 32
    visited_capacity: int = 64
    cam_width_px: int = 352
    cam_height_px: int = 288
    cam_scale: float = 0.0031  # m per px per m of height at 352 px width (DESIGN.md)
    cam_offset_x_m: float = 0.0  # camera mount, body forward
    cam_offset_y_m: float = 0.0  # camera mount, body left
    cam_latency_ms: int = 50
    kf_measurement_std_px: float = 3.0
    kf_accel_psd: float = 400.0  # px^2/s^3
    link_hold_ms: int = 1000  # camera silent this long (9 frames at the paper's 9 fps): hold position
    link_land_ms: int = 10000  # ... this long: give up and land
    # used by the firmware layer (navigation.py), kept here with every other PARAM:
    camera_wait_ms: int = 20000  # before take-off: camera unheard this long -> NO_CAMERA, never take off
    #                              (0: take off without waiting, e.g. a replayed clip that starts in flight)
    frame_capacity: int = 64  # detections kept per frame; more before MARK STOP are dropped (counted)

    @property
    def focal_px(self):
        return (1.0 / self.cam_scale) * self.cam_width_px / 352.0


@dataclass
class Event:
    """A decision worth a console line (and a telemetry STATUSTEXT)."""
    kind: str  # tree_added, tree_evicted, target_selected, tree_reached, recovery, reacquired, abandoned, ...
    t_ms: int
    tree_id: int = 0
    x: float = 0.0
    y: float = 0.0
    detail: str = ""


@dataclass
class Counters:
    detections: int = 0
    out_of_column: int = 0
    on_visited: int = 0
    reached: int = 0
    recoveries: int = 0
    abandoned: int = 0
    link_losses: int = 0
    duplicates: int = 0  # detections merged into another one of the same frame (merge_duplicates)


def rotate(yaw_deg, bx, by):
    """Body (forward, left) -> world."""
    c, s = math.cos(math.radians(yaw_deg)), math.sin(math.radians(yaw_deg))
    return bx * c - by * s, bx * s + by * c


def unrotate(yaw_deg, wx, wy):
    """World -> body (forward, left)."""
    c, s = math.cos(math.radians(yaw_deg)), math.sin(math.radians(yaw_deg))
    return wx * c + wy * s, -wx * s + wy * c


def distance_to_segment(px, py, a, b):
    dx, dy = b[0] - a[0], b[1] - a[1]
    length2 = dx * dx + dy * dy
    t = 0.0 if length2 == 0 else max(0.0, min(1.0, ((px - a[0]) * dx + (py - a[1]) * dy) / length2))
    return math.hypot(px - a[0] - t * dx, py - a[1] - t * dy)


def servo_velocity(offset_fwd_m, offset_left_m, gain, max_speed, integral=(0.0, 0.0), integral_gain=0.0):
    """Visual-servo law: body velocity towards the target, proportional to its metric image offset (plus an
    optional integral term) and saturated (direction kept) at ``max_speed``."""
    vx = gain * offset_fwd_m + integral_gain * integral[0]
    vy = gain * offset_left_m + integral_gain * integral[1]
    speed = math.hypot(vx, vy)
    if speed > max_speed > 0:
        vx, vy = vx * max_speed / speed, vy * max_speed / speed
    return vx, vy


def merge_duplicates(detections, points, radius_m):
    """Detections of one frame closer than ``radius_m`` on the ground are one tree seen twice (overlapping
    detector windows on one large crown): distinct trees stand at least a crown apart. Greedy, in line
    order: each detection joins the first kept one within the radius (running mean of pixel and ground
    position) or is kept. Returns ([(Detection, (x, y)), ...] kept, index into it for every detection)."""
    kept, counts, owner = [], [], []
    for det, (x, y) in zip(detections, points):
        for k, (other, (ox, oy)) in enumerate(kept):
            if math.hypot(x - ox, y - oy) < radius_m:
                n = counts[k] + 1
                kept[k] = (Detection(other.u + (det.u - other.u) / n, other.v + (det.v - other.v) / n),
                           (ox + (x - ox) / n, oy + (y - oy) / n))
                counts[k] = n
                owner.append(k)
                break
        else:
            kept.append((det, (x, y)))
            counts.append(1)
            owner.append(len(kept) - 1)
    return kept, owner


class NavigationCore(object):
    """Algorithm 1. Call ``on_frame`` with each camera frame's detections and ``step`` every control tick."""

    def __init__(self, params, flight_path):
        if len(flight_path) < 2:
            raise ValueError("the flight path needs at least 2 waypoints")
        self.params = params
        self.path = tuple((float(x), float(y)) for x, y in flight_path)
        self.memory = TreeMemory(params.tree_capacity, params.visited_capacity)
        self.counters = Counters()
        self.phase = PHASE_BOOT
        self.waypoint_index = 0  # the waypoint being flown to
        self.target_id = 0  # 0 = none
        self.filter = None
        self.events = []  # drained by the caller
        self._phase_since = 0
        self._settle_since = None
        self._recovery_since = None
        self._target_since = 0
        self._last_tick = None
        self._poses = deque(maxlen=POSE_HISTORY_LENGTH)  # (t_ms, Pose)
        self.pixel_error = (0.0, 0.0)
        self.last_frame_points = []  # world positions of the last frame's detections
        self.captured = False
        self._captured_since = None
        self._servo_integral = (0.0, 0.0)
        self.last_frame_ms = None  # camera link watch: time of the last end-of-frame mark (None: not watched)
        self.link_lost = False
        self.link_aborted = False
        self.revisiting = False  # flying back, before landing, to a tree abandoned while hidden
        self._revisit_arrived = False  # ... and over its stored s_t once

    # -- geometry -----------------------------------------------------------------------------------------

    def camera_ground_point(self, pose):
        ox, oy = rotate(pose.yaw_deg, self.params.cam_offset_x_m, self.params.cam_offset_y_m)
        return pose.x + ox, pose.y + oy

    def pixel_to_world(self, u, v, pose):
        """DESIGN.md camera model: body offset = ((H/2 - v), (W/2 - u)) * z / f, rotated by yaw."""
        p = self.params
        scale = max(pose.z, 0.05) / p.focal_px
        fwd, left = (p.cam_height_px / 2.0 - v) * scale, (p.cam_width_px / 2.0 - u) * scale
        wx, wy = rotate(pose.yaw_deg, fwd, left)
        cx, cy = self.camera_ground_point(pose)
        return cx + wx, cy + wy

    def current_segment(self):
        k = max(self.waypoint_index, 1)
        k = min(k, len(self.path) - 1)
        return self.path[k - 1], self.path[k]

    def in_planting_column(self, x, y):
        a, b = self.current_segment()
        return distance_to_segment(x, y, a, b) <= self.params.column_factor * self.params.crown_size_m

    def _pose_at(self, t_ms):
        """The newest recorded pose not later than ``t_ms`` (the oldest kept one if none)."""
        best = None
        for t, pose in reversed(self._poses):
            best = pose
            if t <= t_ms:
                break
        return best

    # -- camera input -------------------------------------------------------------------------------------

    def on_frame_mark(self, t_ms):
        """The camera finished a frame (with or without detections): the link is alive."""
        self.last_frame_ms = t_ms

    def on_frame(self, t_ms, detections, pose_now):
        """Handle the detections of one camera frame, received at ``t_ms`` (captured cam_latency_ms earlier).

        Returns, per detection, the id of the stored or visited tree it was associated with (0: ignored,
        outside the planting column or no room in T_d)."""
        p = self.params
        pose_capture = self._pose_at(t_ms - p.cam_latency_ms) or pose_now
        points = [self.pixel_to_world(d.u, d.v, pose_capture) for d in detections]
        self.last_frame_points = points
        merged, owner = merge_duplicates(detections, points, p.duplicate_radius_m)
        self.counters.duplicates += len(detections) - len(merged)
        assignment = self.memory.associate([point for _, point in merged], p.merge_radius_m)
        protected = {tree_id for kind, tree_id in assignment if kind == "tree"}
        mav_xy = (pose_now.x, pose_now.y)
        merged_ids = []
        for (det, (wx, wy)), (kind, tree_id) in zip(merged, assignment):
            merged_ids.append(self._take_detection(t_ms, det, wx, wy, kind, tree_id, protected, mav_xy,
                                                   pose_capture, pose_now))
        self.counters.detections += len(detections)
        return [merged_ids[k] for k in owner]

    def _take_detection(self, t_ms, det, wx, wy, kind, tree_id, protected, mav_xy, pose_capture, pose_now):
        """One (de-duplicated) detection of a frame -> the id of its tree (0: ignored)."""
        if kind == "visited":
            self.counters.on_visited += 1
            return tree_id
        if kind is None:
            if not self.in_planting_column(wx, wy):
                self.counters.out_of_column += 1
                return 0
            tree_id, evicted = self.memory.add(wx, wy, t_ms, det.u, det.v, mav_xy, protected)
            for gone in evicted:
                self.events.append(Event("tree_evicted", t_ms, gone, detail="T_d full"))
                if gone == self.target_id:
                    self._drop_target()
            if not tree_id:
                return 0  # T_d full of trees seen in this very frame: counted in memory.unstored
            protected.add(tree_id)  # a later new tree of this frame must not evict this one
            self.events.append(Event("tree_added", t_ms, tree_id, wx, wy))
        else:
            self.memory.update(tree_id, wx, wy, t_ms, det.u, det.v)
        if tree_id == self.target_id:
            self._measure_target(t_ms, det, pose_capture, pose_now)
        return tree_id

    def _ego_corrected(self, det, pose_capture, pose_now):
        """The measured pixel moved to where the tree appears now, given the MAV's motion since capture."""
        fwd, left = unrotate(pose_now.yaw_deg, pose_now.x - pose_capture.x, pose_now.y - pose_capture.y)
        scale = self.params.focal_px / max(pose_now.z, 0.05)
        return det.u + left * scale, det.v + fwd * scale

    def _measure_target(self, t_ms, det, pose_capture, pose_now):
        u, v = self._ego_corrected(det, pose_capture, pose_now)
        if self.phase == PHASE_RECOVERY:
            self.events.append(Event("reacquired", t_ms, self.target_id))
            self._start_tracking(t_ms, u, v)
            return
        if self.filter is None:
            return
        self._predict_filter(t_ms)
        self.filter.update(u, v)

    # -- control tick -------------------------------------------------------------------------------------

    def step(self, t_ms, pose):
        """One control tick: returns the Command to send."""
        self._poses.append((t_ms, pose))
        self.memory.capacity = max(1, int(self.params.tree_capacity))  # PARAMs may change in flight
        self.memory.visited_capacity = max(1, int(self.params.visited_capacity))
        for gone in self.memory.evict_to_capacity((pose.x, pose.y)):
            self.events.append(Event("tree_evicted", t_ms, gone, detail="treeCapacity lowered"))
            if gone == self.target_id:
                self._drop_target()
        hold = self._watch_link(t_ms)
        if hold is not None:
            self._last_tick = t_ms
            return hold
        handler = {PHASE_BOOT: self._step_boot, PHASE_TAKEOFF: self._step_takeoff,
                   PHASE_FOLLOW_PATH: self._step_follow, PHASE_RETURN_TO_PATH: self._step_follow,
                   PHASE_APPROACH: self._step_approach, PHASE_RECOVERY: self._step_recovery,
                   PHASE_LAND: self._step_land, PHASE_DONE: self._step_done,
                   PHASE_NO_DECK: self._step_done, PHASE_NO_CAMERA: self._step_done}[self.phase]
        command = handler(t_ms, pose)
        self._last_tick = t_ms
        return command

    def _watch_link(self, t_ms):
        """Hold (a Command) while the camera link is silent in flight, land when it stays silent; else None."""
        flying = self.phase in (PHASE_FOLLOW_PATH, PHASE_RETURN_TO_PATH, PHASE_APPROACH, PHASE_RECOVERY)
        if self.last_frame_ms is None or not flying:
            return None
        silent_ms = t_ms - self.last_frame_ms
        p = self.params
        if silent_ms > p.link_land_ms:
            self.link_lost, self.link_aborted = False, True
            self.events.append(Event("link_lost", t_ms, detail="camera silent %.1f s: landing" % (silent_ms / 1e3)))
            self._drop_target()
            self._enter(PHASE_LAND, t_ms)
            return self._step_land(t_ms, None)
        if silent_ms > p.link_hold_ms:
            if not self.link_lost:
                self.link_lost = True
                self.counters.link_losses += 1
                self.events.append(Event("link_lost", t_ms, detail="camera silent: holding position"))
            return self._hover()
        if self.link_lost:
            self.link_lost = False
            self.events.append(Event("link_restored", t_ms, detail="after %.1f s" % (silent_ms / 1e3)))
        return None

    def start(self, t_ms):
        self._enter(PHASE_TAKEOFF, t_ms)

    def abort_no_deck(self, t_ms):
        self._enter(PHASE_NO_DECK, t_ms)

    def abort_no_camera(self, t_ms):
        """The app never heard the camera before take-off: stay on the ground (null setpoints)."""
        self._enter(PHASE_NO_CAMERA, t_ms)

    def _enter(self, phase, t_ms, detail=""):
        if phase != self.phase:
            self.phase = phase
            self._phase_since = t_ms
            self.events.append(Event("phase", t_ms, self.target_id, detail=PHASE_NAMES[phase] + detail))

    def _hover(self, vx=0.0, vy=0.0):
        return Command("hover", vx, vy, self.params.altitude_m)

    def _step_boot(self, t_ms, pose):
        return Command("null", 0.0, 0.0, 0.0)

    _step_done = _step_boot

    def _step_takeoff(self, t_ms, pose):
        if abs(pose.z - self.params.altitude_m) > self.params.takeoff_tolerance_m:
            self._settle_since = None
        elif self._settle_since is None:
            self._settle_since = t_ms
        elif t_ms - self._settle_since >= self.params.takeoff_settle_ms:
            self._settle_since = None
            self._enter(PHASE_FOLLOW_PATH, t_ms)
        return self._hover()

    def _step_land(self, t_ms, pose):
        p = self.params
        elapsed = t_ms - self._phase_since
        if elapsed < p.land_step_ms:
            return Command("hover", 0.0, 0.0, p.land_height_m)
        if elapsed < 2 * p.land_step_ms:
            return Command("hover", 0.0, 0.0, p.land_final_m)
        self._enter(PHASE_DONE, t_ms)
        return Command("null", 0.0, 0.0, 0.0)

    # -- path following -----------------------------------------------------------------------------------

    def _step_follow(self, t_ms, pose):
        if self._select_target(t_ms, pose):
            return self._step_approach(t_ms, pose) if self.phase == PHASE_APPROACH else \
                self._step_recovery(t_ms, pose)
        p = self.params
        goal = self.path[self.waypoint_index]
        if self._waypoint_reached(pose):
            self.waypoint_index += 1
            self.events.append(Event("waypoint", t_ms, detail="%d" % (self.waypoint_index - 1)))
            if self.waypoint_index >= len(self.path):
                if self._start_revisit(t_ms, pose):
                    return self._step_recovery(t_ms, pose)
                self._enter(PHASE_LAND, t_ms)
                return self._step_land(t_ms, pose)
            goal = self.path[self.waypoint_index]
        if self.phase == PHASE_RETURN_TO_PATH and self.waypoint_index > 0:
            a, b = self.current_segment()
            if distance_to_segment(pose.x, pose.y, a, b) < p.return_tolerance_m:
                self._enter(PHASE_FOLLOW_PATH, t_ms)
        wx, wy = self._follow_velocity(pose, goal)
        return self._hover(*unrotate(pose.yaw_deg, wx, wy))

    def _waypoint_reached(self, pose):
        """Within ``waypoint_tolerance_m`` of the waypoint, or past the end of the segment towards it
        (a gust can carry the MAV past a 3 cm ball; it must not then circle back for it)."""
        goal = self.path[self.waypoint_index]
        if math.hypot(goal[0] - pose.x, goal[1] - pose.y) < self.params.waypoint_tolerance_m:
            return True
        if self.waypoint_index == 0:
            return False
        a = self.path[self.waypoint_index - 1]
        dx, dy = goal[0] - a[0], goal[1] - a[1]
        return (pose.x - goal[0]) * dx + (pose.y - goal[1]) * dy >= 0.0

    def _follow_velocity(self, pose, goal):
        """World velocity: towards a carrot on the current segment (or straight to the first waypoint)."""
        p = self.params
        if self.waypoint_index == 0:
            carrot = goal
        else:
            a, b = self.path[self.waypoint_index - 1], goal
            dx, dy = b[0] - a[0], b[1] - a[1]
            length = math.hypot(dx, dy) or 1e-9
            along = ((pose.x - a[0]) * dx + (pose.y - a[1]) * dy) / length
            s = min(max(along, 0.0) + p.lookahead_m, length) / length
            carrot = (a[0] + s * dx, a[1] + s * dy)
        ex, ey = carrot[0] - pose.x, carrot[1] - pose.y
        distance = math.hypot(ex, ey)
        if distance < 1e-9:
            return 0.0, 0.0
        to_goal = math.hypot(goal[0] - pose.x, goal[1] - pose.y)
        speed = min(p.cruise_speed, max(p.arrival_min_speed, to_goal))
        return ex / distance * speed, ey / distance * speed

    # -- target selection and visual approach -------------------------------------------------------------

    def eligible_trees(self):
        p = self.params
        return [t for t in self.memory.trees.values()
                if t.hits >= p.min_hits and self.in_planting_column(t.x, t.y)]

    def _select_target(self, t_ms, pose):
        candidates = self.eligible_trees()
        if not candidates:
            return False
        cx, cy = self.camera_ground_point(pose)
        tree = min(candidates, key=lambda t: (math.hypot(t.x - cx, t.y - cy), t.id))
        self.target_id = tree.id
        self._target_since = t_ms
        self.events.append(Event("target_selected", t_ms, tree.id, tree.x, tree.y))
        pose_capture = self._pose_at(tree.last_ms - self.params.cam_latency_ms) or pose
        if t_ms - tree.last_ms > self.params.lost_timeout_ms:
            # seen earlier but not in view now (e.g. during the climb): go to s_t by memory first; this is
            # the recovery manoeuvre, but not a lost target, so it is not counted as a recovery
            self._begin_recovery(t_ms, tree, 0.0, counted=False)
            return True
        u, v = self._ego_corrected(Detection(tree.u, tree.v), pose_capture, pose)
        self._start_tracking(t_ms, u, v)
        return True

    def _start_tracking(self, t_ms, u, v):
        p = self.params
        self.filter = PixelKalmanFilter(u, v, p.kf_measurement_std_px, p.kf_accel_psd)
        self._filter_t_ms = t_ms
        self._settle_since = None
        self._captured_since = None
        self._servo_integral = (0.0, 0.0)
        self._recovery_since = None
        self._enter(PHASE_APPROACH, t_ms)

    def _predict_filter(self, t_ms):
        if t_ms > self._filter_t_ms:
            self.filter.predict((t_ms - self._filter_t_ms) / 1000.0)  # real time, in seconds
            self._filter_t_ms = t_ms

    def _drop_target(self):
        self.target_id = 0
        self.filter = None
        self.captured = False

    def _step_approach(self, t_ms, pose):
        p = self.params
        tree = self.memory.get(self.target_id)
        if tree is None:  # evicted meanwhile: nothing left to approach
            self._drop_target()
            return self._after_tree(t_ms, pose)
        if t_ms - self._target_since > p.target_timeout_ms:
            return self._abandon(t_ms, pose, tree)
        self._predict_filter(t_ms)
        cx, cy = self.camera_ground_point(pose)
        e_d = math.hypot(tree.x - cx, tree.y - cy)
        if e_d > p.recovery_distance_m or t_ms - tree.last_ms > p.lost_timeout_ms:
            return self._start_recovery(t_ms, pose, tree, e_d)
        u, v = self.filter.position
        eu, ev = u - p.cam_width_px / 2.0, v - p.cam_height_px / 2.0
        self.pixel_error = (eu, ev)
        error_px = math.hypot(eu, ev)
        self.captured = error_px < p.capture_radius_px  # the paper's tau: nearly centred
        if not self.captured:
            self._captured_since = None
        elif self._captured_since is None:
            self._captured_since = t_ms
        radius, speed = self.settle_thresholds(t_ms)
        if self.captured and error_px < radius and math.hypot(pose.vx, pose.vy) < speed:
            if self._settle_since is None:
                self._settle_since = t_ms
            if t_ms - self._settle_since >= p.settle_dwell_ms:
                return self._reached(t_ms, pose, tree)
        else:
            self._settle_since = None
        scale = max(pose.z, 0.05) / p.focal_px
        offset = (-ev * scale, -eu * scale)  # metres forward, left
        self._integrate_servo(t_ms, offset, error_px, math.hypot(pose.vx, pose.vy))
        vx, vy = servo_velocity(offset[0], offset[1], p.servo_gain, p.approach_speed, self._servo_integral,
                                p.servo_integral)
        return self._hover(vx, vy)

    def settle_thresholds(self, t_ms):
        """(radius px, speed m/s) of the reached rule, relaxed by ``settle_relax`` per second captured."""
        p = self.params
        if self._captured_since is None:
            return p.settle_radius_px, p.settle_speed
        relax_s = max(0.0, (t_ms - self._captured_since - p.settle_grace_ms) / 1000.0)
        radius = min(p.settle_radius_px + p.settle_relax * relax_s, p.capture_radius_px)
        return radius, p.settle_speed * radius / max(p.settle_radius_px, 1e-9)

    def _integrate_servo(self, t_ms, offset, error_px, speed):
        """Integral of the metric offset, only when a disturbance holds the MAV off the centre: close to it
        (within ``servo_integral_band`` settle radii) yet slower than ``settle_speed``. While the MAV closes
        in nothing is integrated, so a calm approach stays monotonic. Bounded so the integral term alone
        never exceeds half the approach speed."""
        p = self.params
        if error_px > p.servo_integral_band * p.settle_radius_px or p.servo_integral <= 0.0:
            self._servo_integral = (0.0, 0.0)
            return
        if speed >= p.settle_speed:
            return  # still moving: hold the integral
        dt = 0.0 if self._last_tick is None else max(0.0, (t_ms - self._last_tick) / 1000.0)
        ix, iy = self._servo_integral[0] + offset[0] * dt, self._servo_integral[1] + offset[1] * dt
        limit = 0.5 * p.approach_speed / p.servo_integral
        norm = math.hypot(ix, iy)
        if norm > limit:
            ix, iy = ix * limit / norm, iy * limit / norm
        self._servo_integral = (ix, iy)

    def _reached(self, t_ms, pose, tree):
        cx, cy = self.camera_ground_point(pose)
        self.memory.mark_visited(tree.id, t_ms, (pose.x, pose.y), reached=True)
        self.counters.reached += 1
        self.events.append(Event("tree_reached", t_ms, tree.id, cx, cy,
                                 detail="s_t %.3f %.3f" % (tree.x, tree.y)))
        self._drop_target()
        return self._after_tree(t_ms, pose)

    def _after_tree(self, t_ms, pose):
        """A target is done (reached, abandoned or evicted): back to the path, or, while going back for
        abandoned trees after the last waypoint, on to the next one or to landing."""
        if not self.revisiting:
            self._enter(PHASE_RETURN_TO_PATH, t_ms)
            return self._hover()
        self.revisiting = False
        if self._start_revisit(t_ms, pose):
            return self._hover()
        self._enter(PHASE_LAND, t_ms)
        return self._step_land(t_ms, pose)

    def _start_revisit(self, t_ms, pose):
        """Go back once for the nearest tree abandoned while hidden (flagged in the visited list): restore it
        into T_d as the target and fly to s_t by memory. False if there is none."""
        flagged = [e for e in self.memory.visited if e.revisit]
        if not flagged:
            return False
        cx, cy = self.camera_ground_point(pose)
        entry = min(flagged, key=lambda e: (math.hypot(e.x - cx, e.y - cy), e.id))
        p = self.params
        tree, evicted = self.memory.restore(entry.id, p.min_hits, p.cam_width_px / 2.0, p.cam_height_px / 2.0,
                                            (pose.x, pose.y))
        for gone in evicted:
            self.events.append(Event("tree_evicted", t_ms, gone, detail="T_d full"))
        self.revisiting, self._revisit_arrived = True, False
        self.target_id = tree.id
        self._target_since = t_ms
        self.events.append(Event("revisit", t_ms, tree.id, tree.x, tree.y, detail="abandoned while hidden"))
        self._begin_recovery(t_ms, tree, 0.0, counted=False)
        return True

    # -- recovery -----------------------------------------------------------------------------------------

    def _start_recovery(self, t_ms, pose, tree, e_d):
        self._begin_recovery(t_ms, tree, e_d)
        return self._step_recovery(t_ms, pose)

    def _begin_recovery(self, t_ms, tree, e_d, counted=True):
        self.counters.recoveries += int(counted)
        self._recovery_since = t_ms
        self.filter = None
        why = "e_d %.2f m" % e_d if e_d > self.params.recovery_distance_m else "not seen %d ms" % (
            t_ms - tree.last_ms)
        self.events.append(Event("recovery" if counted else "approach_by_memory", t_ms, tree.id, tree.x, tree.y,
                                 detail=why))
        self._enter(PHASE_RECOVERY, t_ms)

    def _abandon(self, t_ms, pose, tree, unseen=False):
        """Give the target up. ``unseen``: recovery timed out without seeing it again (hidden); such a tree is
        flagged for one more try before landing, unless this already was that try."""
        if tree is not None:
            revisit = unseen and not self.revisiting
            self.memory.mark_visited(tree.id, t_ms, (pose.x, pose.y), reached=False, revisit=revisit)
            self.counters.abandoned += 1
            self.events.append(Event("abandoned", t_ms, tree.id, tree.x, tree.y,
                                     detail="unseen: will go back once" if revisit else ""))
        self._drop_target()
        return self._after_tree(t_ms, pose)

    def _step_recovery(self, t_ms, pose):
        p = self.params
        tree = self.memory.get(self.target_id)
        cx, cy = self.camera_ground_point(pose)
        ex, ey = (tree.x - cx, tree.y - cy) if tree is not None else (0.0, 0.0)
        distance = math.hypot(ex, ey)
        if self.revisiting and not self._revisit_arrived and tree is not None:
            # going back: the recovery and target clocks start once the MAV is over s_t
            self._revisit_arrived = distance <= p.return_tolerance_m
            self._recovery_since = self._target_since = t_ms
        if tree is None or t_ms - self._target_since > p.target_timeout_ms:
            return self._abandon(t_ms, pose, tree)
        if t_ms - self._recovery_since > p.recovery_timeout_ms:
            return self._abandon(t_ms, pose, tree, unseen=True)
        speed = min(p.recovery_speed, p.servo_gain * distance)
        if distance < 1e-9:
            return self._hover()
        return self._hover(*unrotate(pose.yaw_deg, ex / distance * speed, ey / distance * speed))
