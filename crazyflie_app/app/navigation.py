"""The ForaNav Bolt navigation app (a port of ``Navigation/Navigation.c``) on the emulated firmware.

The algorithm lives in the pure core (``navigation_core.NavigationCore``, with ``pixel_kalman`` and
``tree_memory``); this module is the thin firmware layer around it, shaped like the C app: ``app_main.app_main`` waits
for the system, checks the decks, then loops every 10 ms reading ``stateEstimate.*``, stepping the core and
sending its setpoint at ``COMMANDER_PRIORITY_EXTRX``; ``camera_task`` reads the JeVois lines from the serial
link and hands each frame's detections to the core. PARAM and LOG tables are declared at the bottom.

C -> Python names (Navigation.c -> here)::

    appMain()                          app_main.app_main(app)  (a task generator, shared with the C app)
    setHoverSetpoint(sp, vx, vy, z, yaw)
                                       set_hover_setpoint(sp, vx, vy, z, yaw)  (body velocity, abs z and yaw)
    memset(&setpoint, 0, ...)          set_null_setpoint(sp)  (motors off)
    cpxPacketCallback(cpxRx)           NavigationApp.camera_task() + on_camera_line(line)  (text over UART)
    is_at_target_mainroad()            path_following.PathFollower.waypoint_reached() / follow_velocity()
    drone_speed() / drone_speed2()     PathFollower.follow_velocity() / visual_servo.servo_velocity()
    Move_to_TreeTop()                  NavigationCore._step_approach()  (non-blocking, one tick per call)
    is_at_target() (0.7 m switch)      NavigationCore._step_approach() -> _begin_recovery()  (app.recoveryDist)
    kalmanFilterInit/Predict/Update()  pixel_kalman.PixelKalmanFilter(), .predict(dt_s), .update(u, v)
    trees[], numTrees                  tree_memory.TreeMemory.trees  (dict by stable id), LOG app.numTrees
    treeBlacklist[]                    tree_memory.TreeMemory.visited  (bounded), LOG app.numVisited
    removeCoordinate()                 TreeMemory.mark_visited()
    logGetVarId() + logGetFloat()      ids resolved once in app_main, read with log_get_float()
    paramGetUint(deck.bcFlow2)         the same, plus deck.bcLoco (a warning: without it the estimate drifts)
    (none: the CF2 auto-arms)          cf.supervisor_request_arming(True) after the checks (the Bolt needs it)
    DEBUG_PRINT(...)                   Crazyflie.debug_print(DEBUG_MODULE, ...)

The C app's known weaknesses and what this port does about each (tests named in brackets):

* **Out-of-bounds covariance terms** (``P`` is ``float[2][2]`` but ``P[2][2]``, ``P[3][3]`` are used): the filter
  keeps the full 4x4 covariance of ``[u, v, du, dv]`` with a Joseph-form update, so P stays symmetric
  positive definite [test_pixel_kalman: the covariance is the full 4x4 matrix ...].
* **Filter on a wrong time base** (dt = 0.001 per 10 ms loop): the filter is predicted every control tick
  with the tick's real duration in seconds, and detections are shifted by the MAV's motion since capture
  [test_pixel_kalman: prediction runs in real seconds ...].
* **Dead return-to-path branch** (``checkReturnToPath`` could only ever be true): RETURN_TO_PATH is a real
  phase entered after every tree, left when the cross-track error is below ``returnTol``
  [test_navigation_core: return to path runs after a tree ...].
* **Stale target index after removal** (``KalmantreeNum`` indexed an array that ``removeCoordinate``
  shifted): trees are keyed by stable ids; removing or evicting a tree never retargets another one
  [test_tree_memory: ids stay valid ...; test_navigation_core: the target survives the removal ...].
* **Unbounded visited list** (``treeBlacklist[10]`` overflowed on the 11th tree) and the silent 10-tree cap:
  both collections have PARAM capacities; overflow evicts the farthest entry and is counted in LOG
  variables (``app.evicted``, ``app.forgotten``) and printed, never silent [test_tree_memory: the
  visited list is bounded ...; a full memory evicts the farthest tree ...].

Also changed from the C app: ids of log/param variables are looked up once, not on every call;
``deck.bcLoco`` is checked; the camera input task never sleeps 100 ms inside the callback; tree positions
use the estimate at *capture* time (``camLatency``); serial text lines (JeVois standardized ``T2``/``N2``)
replace the CPX bytes, so the 255-column byte limit of the C protocol is gone.
"""
import math
from collections.abc import Iterator, Sequence

from jevois_module.ForaNavTrees import foranav_serial
from crazyflie_app.app.app_main import CAMERA_TASK_PERIOD_MS, DEBUG_MODULE, app_init, format_fixed
from crazyflie_app.app.app_main import BOOT_DELAY_MS, PRE_TAKEOFF_DELAY_MS  # noqa: F401 (the app's boot timing)
from crazyflie_app.firmware.commander import setpoint_t
from crazyflie_app.firmware.freertos import Delay, m2t, v_task_delay
from crazyflie_app.firmware.logparam import (LOG_FLOAT, LOG_UINT8, LOG_UINT16, LOG_UINT32, PARAM_FLOAT, PARAM_UINT8,
                                              PARAM_UINT16, PARAM_UINT32, log_add, log_group, param_add, param_group)
from crazyflie_app.firmware.system import Crazyflie
from crazyflie_app.app.navigation_core import (PHASE_DONE, PHASE_NO_CAMERA, Detection, NavigationCore,
                                           NavigationParams, Pose)
from crazyflie_app.app.serial_link import SerialLink
from crazyflie_app.app.uart2_link import Uart2Link


class NavigationApp:
    """One instance of the app on one emulated Crazyflie.

    ``flight_path`` is the path F (waypoints [(x, y), ...], metres; compiled-in constants in the C app);
    ``serial_url`` the camera port (a device, a pty path or ``loop://``); ``target_label``: the species label
    of ``N2`` lines to act on (``T2`` lines carry no label and are always taken).
    """

    def __init__(self, cf: Crazyflie, flight_path: Sequence[tuple[float, float]], serial_url: str | None,
                 params: NavigationParams | None = None, link: SerialLink | Uart2Link | None = None,
                 target_label: str | None = None):
        self.cf = cf
        self.target_label = target_label  # N2 lines with another label are ignored (None: accept all)
        self.other_labels = 0
        self.params = params or NavigationParams()
        self.core = NavigationCore(self.params, flight_path)
        self.link = link or SerialLink(serial_url)
        self.setpoint = setpoint_t()  # static setpoint_t setpoint;
        self._frame = []  # detections of the frame being received (at most app.frameCap)
        self._marks_seen = False  # the camera sends MARK START/STOP: frames are delimited by them
        self.frames = 0
        self.last_detection_ms = -1
        self.last_heard_ms = -1  # last valid camera message (frame mark or detection); -1: never heard
        self.frame_overflow = 0  # detections dropped: more than app.frameCap in one frame
        self.estimate_ids = None  # the stateEstimate log ids, resolved by app_main
        cf.registry.register_param_group(PARAM_TABLE, self.params)
        cf.registry.register_log_group(LOG_TABLE, self)

    def start(self) -> None:
        """appInit(): the app task (``app_main.app_main``: checks, arming, the 10 ms loop) and the camera task."""
        app_init(self)

    # -- what the app task asks of the app ----------------------------------------------------------------

    def camera_alive(self, now: int) -> bool:
        """Pre-flight check: a valid camera message within app.linkHoldMs (app.camWaitMs 0: no check)."""
        if self.params.camera_wait_ms <= 0:
            return True
        return self.last_heard_ms >= 0 and now - self.last_heard_ms <= self.params.link_hold_ms

    def read_pose(self) -> Pose:
        return Pose(*[self.cf.log_get_float(var_id) for var_id in self.estimate_ids])

    format_fixed = staticmethod(format_fixed)  # the console's number format

    def print_events(self) -> None:
        for event in self.core.events:
            if event.kind == "phase":
                text = "phase " + event.detail
            else:
                text = "%s tree %d" % (event.kind, event.tree_id) if event.tree_id else event.kind
                if event.kind in ("tree_added", "tree_reached", "target_selected", "recovery", "abandoned",
                                  "approach_by_memory", "revisit"):
                    text += " at (%.3f, %.3f)" % (event.x, event.y)
                if event.detail:
                    text += " " + event.detail
            self.cf.debug_print(DEBUG_MODULE, text)
            self.cf.event_trigger(event.kind, tree_id=event.tree_id, x=event.x, y=event.y)
        del self.core.events[:]

    # -- the camera-input task ----------------------------------------------------------------------------

    def camera_task(self) -> Iterator[Delay]:
        while True:
            for line in self.link.poll(self.cf.x_task_get_tick_count()):
                self.on_camera_line(line)
            self._bound_frame()
            if self._frame and not self._marks_seen:
                self._end_frame()  # a camera without frame marks: each batch of lines is one frame
            yield v_task_delay(m2t(CAMERA_TASK_PERIOD_MS))

    def on_camera_line(self, line: bytes) -> None:
        """One received line: T2/N2 detections are kept for the frame, MARK START/STOP delimit frames, and
        everything else (OK, ERR ..., ALIVE, noise) is ignored."""
        message = foranav_serial.parse_line(line)
        if isinstance(message, (foranav_serial.FrameMark, foranav_serial.Target2D)):
            self.last_heard_ms = self.cf.x_task_get_tick_count()
        if isinstance(message, foranav_serial.FrameMark):
            self._marks_seen = True
            self.core.on_frame_mark(self.cf.x_task_get_tick_count())
            self._end_frame()
        elif isinstance(message, foranav_serial.Target2D):
            if message.kind == "N2" and self.target_label is not None and message.label != self.target_label:
                self.other_labels += 1
                return
            p = self.params
            if not self._bound_frame():
                self.frame_overflow += 1  # T2 lines without MARK STOP must not pile up without limit
                return
            self._frame.append(Detection(foranav_serial.std_to_img_x(message.x, p.cam_width_px),
                                         foranav_serial.std_to_img_y(message.y, p.cam_height_px)))

    def _bound_frame(self) -> bool:
        """Keep the frame being received within app.frameCap (a PARAM that may be lowered in flight); True
        if there is room for one more detection."""
        cap = max(0, int(self.params.frame_capacity))
        if len(self._frame) > cap:
            self.frame_overflow += len(self._frame) - cap
            del self._frame[cap:]
        return len(self._frame) < cap

    def _end_frame(self) -> None:
        if not self._frame or self.core.phase in (PHASE_DONE, PHASE_NO_CAMERA) \
                or self.estimate_ids is None:
            self._frame = []
            return
        now = self.cf.x_task_get_tick_count()
        pose = self.read_pose()
        detections, self._frame = self._frame, []
        ids = self.core.on_frame(now, detections, pose)
        self.frames += 1
        self.last_detection_ms = now
        for det, tree_id, (wx, wy) in zip(detections, ids, self.core.last_frame_points):
            self.cf.event_trigger("detection", u=det.u, v=det.v, tree_id=tree_id, z=pose.z, x=wx, y=wy)
        self.print_events()

    # -- LOG variables ------------------------------------------------------------------------------------

    phase = property(lambda self: self.core.phase)
    target_id = property(lambda self: self.core.target_id)
    num_trees = property(lambda self: len(self.core.memory))
    num_visited = property(lambda self: len(self.core.memory.visited))
    waypoint_index = property(lambda self: self.core.waypoint_index)
    reached = property(lambda self: self.core.counters.reached)
    recoveries = property(lambda self: self.core.counters.recoveries)
    abandoned = property(lambda self: self.core.counters.abandoned)
    detections = property(lambda self: self.core.counters.detections)
    out_of_column = property(lambda self: self.core.counters.out_of_column)
    pending_detections = property(lambda self: len(self._frame))  # of the frame being received
    evicted = property(lambda self: self.core.memory.evicted)
    unstored = property(lambda self: self.core.memory.unstored)
    duplicates = property(lambda self: self.core.counters.duplicates)
    forgotten = property(lambda self: self.core.memory.visited_forgotten)
    captured = property(lambda self: int(self.core.captured))
    err_u = property(lambda self: self.core.pixel_error[0])
    err_v = property(lambda self: self.core.pixel_error[1])
    link_dropped = property(lambda self: self.link.lines_dropped)
    link_opens = property(lambda self: self.link.opens)
    link_lost = property(lambda self: int(self.core.link_lost))
    link_losses = property(lambda self: self.core.counters.link_losses)
    target_x = property(lambda self: self._target_coordinate("x"))
    target_y = property(lambda self: self._target_coordinate("y"))

    def _target_coordinate(self, axis: str) -> float:
        tree = self.core.memory.get(self.core.target_id)
        return getattr(tree, axis) if tree else math.nan


# ----------------------------------------------------------------------------------------------------------
# PARAM_GROUP_START(app) ... PARAM_GROUP_STOP(app): every threshold and speed law, with units and the source
# of its default (the paper's flight tests, Navigation.c, or this port's design). ``valid`` is the range a write
# must fall in (a client's write from cfclient or cflib, a flight option): outside it, or NaN, the write is refused
# and the param keeps its value, as an app's PARAM_ADD_WITH_CALLBACK check would put the old value back; a zero
# camera width or a NaN speed would otherwise fly the mission blind or stall it.

PARAM_TABLE = param_group("app", [
    param_add(PARAM_FLOAT, "altitude", "altitude_m", "m", "flight height above ground (paper: 1.25 m)",
              valid=(0.1, 1000.0)),  # 1000: the fault tests fly that high (tests/crazyflie_app/app/test_faults.py)
    param_add(PARAM_FLOAT, "takeoffTol", "takeoff_tolerance_m", "m", "height error that counts as at altitude",
              valid=(0.01, 1.0)),
    param_add(PARAM_UINT16, "takeoffSettle", "takeoff_settle_ms", "ms", "time at altitude before the path starts",
              valid=(0, 65535)),
    param_add(PARAM_FLOAT, "landHeight", "land_height_m", "m", "first landing step height (Navigation.c: 0.5 m)",
              valid=(0.05, 4.0)),
    param_add(PARAM_FLOAT, "landFinal", "land_final_m", "m", "second landing step: from this height down to the ground (Navigation.c held 0.15 m)",
              valid=(0.0, 1.0)),
    param_add(PARAM_UINT16, "landStep", "land_step_ms", "ms", "duration of each landing step (Navigation.c: 3 s)",
              valid=(100, 65535)),
    param_add(PARAM_FLOAT, "cruiseSpeed", "cruise_speed", "m/s", "speed along the path F (paper: <= 0.1 m/s)",
              valid=(0.01, 1.0)),
    param_add(PARAM_FLOAT, "arrivalSpeed", "arrival_min_speed", "m/s",
              "slowest speed of the follow law near a waypoint (it slows down as 1/s x distance)", valid=(0.0, 1.0)),
    param_add(PARAM_FLOAT, "wpTolerance", "waypoint_tolerance_m", "m",
              "distance at which a waypoint counts as reached (Navigation.c: 0.03 m)", valid=(0.005, 2.0)),
    param_add(PARAM_FLOAT, "lookahead", "lookahead_m", "m", "carrot distance ahead on the path segment",
              valid=(0.0, 5.0)),
    param_add(PARAM_FLOAT, "approachSpeed", "approach_speed", "m/s", "visual-servo speed limit (paper: 0.1)",
              valid=(0.01, 1.0)),
    param_add(PARAM_FLOAT, "servoGain", "servo_gain", "1/s", "visual-servo velocity per metre of image offset",
              valid=(0.0, 20.0)),
    param_add(PARAM_FLOAT, "captureRadius", "capture_radius_px", "px",
              "tau: offset at which the tree counts as nearly centred (paper / Navigation.c: 40 px)",
              valid=(1.0, 1000.0)),
    param_add(PARAM_FLOAT, "settleRadius", "settle_radius_px", "px",
              "reached: filtered offset below this (6 px ~ 2.3 cm at 1.25 m) ...", valid=(0.5, 1000.0)),
    param_add(PARAM_UINT16, "settleDwell", "settle_dwell_ms", "ms", "... held this long ...", valid=(0, 65535)),
    param_add(PARAM_FLOAT, "settleSpeed", "settle_speed", "m/s", "... while the MAV is slower than this",
              valid=(0.001, 1.0)),
    param_add(PARAM_FLOAT, "settleRelax", "settle_relax", "px/s",
              "growth of settleRadius (and settleSpeed) per second captured beyond settleGrace, up to "
              "captureRadius", valid=(0.0, 1000.0)),
    param_add(PARAM_UINT16, "settleGrace", "settle_grace_ms", "ms", "captured time before settleRelax starts",
              valid=(0, 65535)),
    param_add(PARAM_FLOAT, "servoKi", "servo_integral", "1/s^2",
              "integral gain of the visual servo, active only when held near but off the centre (wind)",
              valid=(0.0, 10.0)),
    param_add(PARAM_FLOAT, "servoKiBand", "servo_integral_band", "",
              "the servo integrates only inside this many settle radii", valid=(0.0, 100.0)),
    param_add(PARAM_FLOAT, "recoveryDist", "recovery_distance_m", "m",
              "delta: MAV-to-s_t distance that starts recovery (Navigation.c: 0.7 m)", valid=(0.05, 10.0)),
    param_add(PARAM_UINT16, "lostTimeout", "lost_timeout_ms", "ms",
              "target unseen this long during the approach: recovery", valid=(1, 65535)),
    param_add(PARAM_UINT32, "recoveryTimeout", "recovery_timeout_ms", "ms",
              "recovery gives up (tree abandoned) after this long", valid=(1, 4294967295)),
    param_add(PARAM_UINT32, "targetTimeout", "target_timeout_ms", "ms",
              "a target not reached this long after it was selected is abandoned", valid=(1, 4294967295)),
    param_add(PARAM_UINT16, "linkHoldMs", "link_hold_ms", "ms",
              "camera link silent this long in flight: hold position until frames come back", valid=(1, 65535)),
    param_add(PARAM_UINT16, "linkLandMs", "link_land_ms", "ms", "camera link silent this long: land", valid=(1, 65535)),
    param_add(PARAM_UINT16, "camWaitMs", "camera_wait_ms", "ms",
              "before take-off: no camera line heard within linkHoldMs for this long -> NO_CAMERA, stay on the "
              "ground (0: no check)", valid=(0, 65535)),
    param_add(PARAM_UINT8, "frameCap", "frame_capacity", "",
              "detections kept per frame; more before the frame's MARK STOP are dropped (LOG frameOverflow)",
              valid=(1, 255)),
    param_add(PARAM_UINT8, "start", "start", "",
              "0: after its deck checks the app waits on the ground, motors off, until a client writes 1 (then "
              "take-off 3 s later); 1 (default): it starts by itself", valid=(0, 1)),
    param_add(PARAM_FLOAT, "recoverySpeed", "recovery_speed", "m/s", "speed when re-approaching s_t",
              valid=(0.01, 1.0)),
    param_add(PARAM_FLOAT, "returnTol", "return_tolerance_m", "m",
              "cross-track error that ends RETURN_TO_PATH", valid=(0.005, 5.0)),
    param_add(PARAM_FLOAT, "mergeRadius", "merge_radius_m", "m",
              "detections this close to a stored tree are the same tree (Navigation.c: 0.45 m)", valid=(0.01, 10.0)),
    param_add(PARAM_FLOAT, "dupRadius", "duplicate_radius_m", "m",
              "detections of one frame this close are one crown seen twice and merged, and a stored tree this "
              "close to a reached one is that tree (trees stand >= a crown apart)", valid=(0.0, 10.0)),
    param_add(PARAM_FLOAT, "crownSize", "crown_size_m", "m", "crown size of a mature tree (planting column)",
              valid=(0.1, 20.0)),
    param_add(PARAM_FLOAT, "columnFactor", "column_factor", "",
              "planting column half-width in crown sizes (paper: 1.5)", valid=(0.1, 10.0)),
    param_add(PARAM_FLOAT, "rowSpacing", "row_spacing_m", "m",
              "centre distance of adjacent rows (a map's row_spacing_m): the column is at most half of it wide, "
              "a tree belongs to its nearest row (0: not given, columnFactor crowns alone)", valid=(0.0, 100.0)),
    param_add(PARAM_UINT8, "anchorMin", "anchor_min_trees", "",
              "re-anchoring: at each tree reached the row line is corrected from the trees seen then (it and the "
              "column's trees in view) when there are at least this many; the estimate drifts, the rows do not "
              "(0: off, the waypoints in the estimate's frame)", valid=(0, 255)),
    param_add(PARAM_FLOAT, "anchorGain", "anchor_gain", "",
              "re-anchoring: each correction moves the row line this fraction of the way to the trees seen (a tree "
              "planted off its row must not pull in a palm beside it)", valid=(0.0, 1.0)),
    param_add(PARAM_UINT8, "minHits", "min_hits", "", "detections before a tree may become the target", valid=(1, 255)),
    param_add(PARAM_UINT8, "treeCapacity", "tree_capacity", "", "capacity of T_d (overflow evicts, counted)",
              valid=(1, 64)),
    param_add(PARAM_UINT16, "visitedCap", "visited_capacity", "", "capacity of the visited list (counted)",
              valid=(1, 128)),
    param_add(PARAM_UINT16, "camWidth", "cam_width_px", "px", "camera frame width (JeVois 352x288 mode)",
              valid=(16, 4096)),
    param_add(PARAM_UINT16, "camHeight", "cam_height_px", "px", "camera frame height", valid=(16, 4096)),
    param_add(PARAM_FLOAT, "camScale", "cam_scale", "m/px/m",
              "ground size of a pixel per metre of height at 352 px width (0.0031)", valid=(0.0001, 0.1)),
    param_add(PARAM_FLOAT, "camOffsetX", "cam_offset_x_m", "m", "camera mount, body forward (default 0)",
              valid=(-0.5, 0.5)),
    param_add(PARAM_FLOAT, "camOffsetY", "cam_offset_y_m", "m", "camera mount, body left (default 0)",
              valid=(-0.5, 0.5)),
    param_add(PARAM_UINT16, "camLatency", "cam_latency_ms", "ms", "capture-to-reception latency of a frame",
              valid=(0, 2000)),
    param_add(PARAM_FLOAT, "kfMeasStd", "kf_measurement_std_px", "px", "Kalman filter: detection noise std",
              valid=(0.01, 1000.0)),
    param_add(PARAM_FLOAT, "kfAccelPsd", "kf_accel_psd", "px^2/s^3",
              "Kalman filter: white-acceleration spectral density of the image motion", valid=(0.0, 1000000.0)),
])

# LOG_GROUP_START(app) ... LOG_GROUP_STOP(app)
LOG_TABLE = log_group("app", [
    log_add(LOG_UINT8, "phase", "phase", "", "app phase (navigation_core.PHASE_NAMES)"),
    log_add(LOG_UINT16, "targetId", "target_id", "", "id of the target tree t* (0: none)"),
    log_add(LOG_FLOAT, "targetX", "target_x", "m", "stored position s_t of the target"),
    log_add(LOG_FLOAT, "targetY", "target_y", "m", "stored position s_t of the target"),
    log_add(LOG_FLOAT, "errU", "err_u", "px", "filtered image offset e_p, column"),
    log_add(LOG_FLOAT, "errV", "err_v", "px", "filtered image offset e_p, row"),
    log_add(LOG_UINT8, "captured", "captured", "", "1 while e_p < captureRadius"),
    log_add(LOG_UINT8, "numTrees", "num_trees", "", "trees in T_d"),
    log_add(LOG_UINT16, "numVisited", "num_visited", "", "entries in the visited list"),
    log_add(LOG_UINT8, "waypoint", "waypoint_index", "", "index of the waypoint being flown to"),
    log_add(LOG_UINT16, "reached", "reached", "", "trees reached"),
    log_add(LOG_UINT16, "recoveries", "recoveries", "", "recoveries started"),
    log_add(LOG_UINT16, "abandoned", "abandoned", "", "trees given up after a failed recovery"),
    log_add(LOG_UINT32, "detections", "detections", "", "detections received"),
    log_add(LOG_UINT32, "outOfColumn", "out_of_column", "", "detections outside the planting column"),
    log_add(LOG_UINT16, "evicted", "evicted", "", "trees evicted from a full T_d"),
    log_add(LOG_UINT16, "unstored", "unstored", "", "new trees not stored: T_d full of trees of the same frame"),
    log_add(LOG_UINT32, "duplicates", "duplicates", "", "detections merged with another of the same frame"),
    log_add(LOG_UINT32, "frameOverflow", "frame_overflow", "", "detections dropped beyond frameCap in a frame"),
    log_add(LOG_UINT16, "forgotten", "forgotten", "", "visited entries forgotten from a full list"),
    log_add(LOG_UINT32, "linkDropped", "link_dropped", "", "serial lines dropped for length"),
    log_add(LOG_UINT16, "linkOpens", "link_opens", "", "times the serial port was (re)opened"),
    log_add(LOG_UINT8, "linkLost", "link_lost", "", "1 while holding position for a silent camera link"),
    log_add(LOG_UINT16, "linkLosses", "link_losses", "", "times the camera link went silent in flight"),
])
