"""The pure core of the navigation app: Algorithm 1 as a state machine that takes time and measurements as
arguments and returns setpoints and decisions. No clock, serial port, log or commander access here.

Phases (``custom_mode`` in the telemetry heartbeat)::

    BOOT -> TAKEOFF -> FOLLOW_PATH <-> APPROACH <-> RECOVERY
                          ^   |            |            | (timeout: tree abandoned)
                          |   v            v reached    v
                          RETURN_TO_PATH <------------- +
    FOLLOW_PATH (last waypoint) -> [RECOVERY -> APPROACH: go back once per tree abandoned unseen] -> LAND -> DONE
    (null setpoints, motors off);  NO_DECK: no Flow deck, aborted;  NO_CAMERA: camera never heard, never took off

The state machine lives here; each job it calls has its module (composition, no inheritance), whose
docstring describes it: ``nav_types`` (phases, records, ``NavigationParams``), ``camera_geometry`` (pixel <->
ground, the pose at capture, one detection per crown), ``frame_input`` (a frame's detections into T_d),
``vertical`` (TAKEOFF, LAND), ``path_following`` (FOLLOW_PATH, the planting column), ``visual_servo``
(APPROACH: the pixel filter, the servo law, the reached rule), ``recovery`` (RECOVERY, going back once for
hidden trees), ``link_watch`` (a silent camera: hold, then land) and ``tree_memory`` (T_d, the visited list).
This module re-exports their public names. After a tree, RETURN_TO_PATH flies back to the current segment
until the cross-track error is below ``returnTolerance``.
"""
import math
from collections.abc import Sequence

from crazyflie_app.app.camera_geometry import CameraGeometry, PoseHistory, merge_duplicates, rotate, unrotate
from crazyflie_app.app.frame_input import FrameInput
from crazyflie_app.app.link_watch import HOLD, LinkWatch
from crazyflie_app.app.nav_types import (PHASE_APPROACH, PHASE_BOOT, PHASE_DONE, PHASE_FOLLOW_PATH, PHASE_LAND,
                                     PHASE_NAMES, PHASE_NO_CAMERA, PHASE_NO_DECK, PHASE_RECOVERY,
                                     PHASE_RETURN_TO_PATH, PHASE_TAKEOFF, POSE_HISTORY_LENGTH, Command, Counters,
                                     Detection, Event, NavigationParams, Pose)
from crazyflie_app.app.path_following import PathFollower, distance_to_segment
from crazyflie_app.app.recovery import ABANDON, ABANDON_UNSEEN, Recovery, nearest
from crazyflie_app.app.tree_memory import StoredTree, TreeMemory
from crazyflie_app.app.vertical import NULL_COMMAND, TakeoffRule, landing_setpoint
from crazyflie_app.app.visual_servo import VisualServo, servo_velocity

__all__ = ["PHASE_APPROACH", "PHASE_BOOT", "PHASE_DONE", "PHASE_FOLLOW_PATH", "PHASE_LAND", "PHASE_NAMES",
           "PHASE_NO_CAMERA", "PHASE_NO_DECK", "PHASE_RECOVERY", "PHASE_RETURN_TO_PATH", "PHASE_TAKEOFF",
           "POSE_HISTORY_LENGTH", "Command", "Counters", "Detection", "Event", "NavigationCore", "NavigationParams",
           "Pose", "distance_to_segment", "merge_duplicates", "rotate", "servo_velocity", "unrotate"]

FLYING_PHASES = (PHASE_FOLLOW_PATH, PHASE_RETURN_TO_PATH, PHASE_APPROACH, PHASE_RECOVERY)


class NavigationCore:
    """Algorithm 1. Call ``on_frame`` with each camera frame's detections and ``step`` every control tick."""

    def __init__(self, params: NavigationParams, flight_path: Sequence[tuple[float, float]]):
        self.params = params
        self.route = PathFollower(params, flight_path)
        self.camera = CameraGeometry(params)
        self.servo = VisualServo(params, self.camera)
        self.link = LinkWatch(params)
        self.memory = TreeMemory(params.tree_capacity, params.visited_capacity)
        self.counters = Counters()
        self.frames = FrameInput(params, self.route, self.memory, self.counters)
        self.recovery = Recovery(params)
        self.takeoff = TakeoffRule(params)
        self.phase = PHASE_BOOT
        self.target_id = 0  # 0 = none
        self.events = []  # drained by the caller
        self._phase_since = 0
        self._last_tick = None
        self._poses = PoseHistory()
        self.last_frame_points = []  # world positions of the last frame's detections

    # -- the components' state, under the names the app, the harness and the tests read -----------------

    path = property(lambda self: self.route.path)
    pixel_error = property(lambda self: self.servo.pixel_error)
    captured = property(lambda self: self.servo.captured)
    link_lost = property(lambda self: self.link.link_lost)
    link_aborted = property(lambda self: self.link.link_aborted)
    revisiting = property(lambda self: self.recovery.revisiting)
    waypoint_index = property(lambda self: self.route.waypoint_index,
                              lambda self, index: setattr(self.route, "waypoint_index", index))

    def pixel_to_world(self, u: float, v: float, pose: Pose) -> tuple[float, float]:
        return self.camera.pixel_to_world(u, v, pose)

    def in_planting_column(self, x: float, y: float) -> bool:
        return self.route.in_planting_column(x, y)

    # -- camera input -------------------------------------------------------------------------------------

    def on_frame_mark(self, t_ms: int) -> None:
        """The camera finished a frame (with or without detections): the link is alive."""
        self.link.on_frame_mark(t_ms)

    def on_frame(self, t_ms: int, detections: Sequence[Detection], pose_now: Pose) -> list[int]:
        """Handle the detections of one camera frame, received at ``t_ms`` (captured cam_latency_ms earlier).

        Returns, per detection, the id of the stored or visited tree it was associated with (0: ignored,
        outside the planting column or no room in T_d)."""
        pose_capture = self._poses.at(t_ms - self.params.cam_latency_ms) or pose_now
        points = [self.camera.pixel_to_world(d.u, d.v, pose_capture) for d in detections]
        self.last_frame_points = points
        ids = self.frames.take(t_ms, detections, points, (pose_now.x, pose_now.y), self.events,
                               lambda: self.target_id, self._evicted,
                               lambda t, det: self._measure_target(t, det, pose_capture, pose_now))
        for gone, twin in self.memory.absorb_reached(self.params.duplicate_radius_m, t_ms, (pose_now.x, pose_now.y)):
            self.events.append(Event("tree_absorbed", t_ms, gone, detail="reached tree %d" % twin))
            if gone == self.target_id:
                self._drop_target()
        return ids

    def _evicted(self, t_ms, evicted, why):
        for gone in evicted:
            self.events.append(Event("tree_evicted", t_ms, gone, detail=why))
            if gone == self.target_id:
                self._drop_target()

    def _measure_target(self, t_ms, det, pose_capture, pose_now):
        u, v = self.camera.ego_corrected(det, pose_capture, pose_now)
        if self.phase == PHASE_RECOVERY:
            self.events.append(Event("reacquired", t_ms, self.target_id))
            self._start_tracking(t_ms, u, v)
            return
        self.servo.measure(t_ms, u, v)

    # -- control tick -------------------------------------------------------------------------------------

    def step(self, t_ms: int, pose: Pose) -> Command:
        """One control tick: returns the Command to send."""
        self._poses.append(t_ms, pose)
        self.memory.capacity = max(1, int(self.params.tree_capacity))  # PARAMs may change in flight
        self.memory.visited_capacity = max(1, int(self.params.visited_capacity))
        self._evicted(t_ms, self.memory.evict_to_capacity((pose.x, pose.y)), "treeCapacity lowered")
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
        action = self.link.check(t_ms, self.phase in FLYING_PHASES, self.events, self.counters)
        if action is None:
            return None
        if action == HOLD:
            return self._hover()
        self._drop_target()
        self._enter(PHASE_LAND, t_ms)
        return self._step_land(t_ms, None)

    def start(self, t_ms: int) -> None:
        self._enter(PHASE_TAKEOFF, t_ms)

    def abort_no_deck(self, t_ms: int) -> None:
        self._enter(PHASE_NO_DECK, t_ms)

    def abort_no_camera(self, t_ms: int) -> None:
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
        return NULL_COMMAND

    _step_done = _step_boot

    def _step_takeoff(self, t_ms, pose):
        if self.takeoff.done(t_ms, pose):
            self._enter(PHASE_FOLLOW_PATH, t_ms)
        return self._hover()

    def _step_land(self, t_ms, pose):
        command = landing_setpoint(self.params, t_ms - self._phase_since)
        if command is None:
            self._enter(PHASE_DONE, t_ms)
            return NULL_COMMAND
        return command

    # -- path following -----------------------------------------------------------------------------------

    def _step_follow(self, t_ms, pose):
        if self._select_target(t_ms, pose):
            return self._step_approach(t_ms, pose) if self.phase == PHASE_APPROACH else \
                self._step_recovery(t_ms, pose)
        route = self.route
        goal = route.goal
        if route.waypoint_reached(pose):
            route.advance()
            self.events.append(Event("waypoint", t_ms, detail="%d" % (route.waypoint_index - 1)))
            if route.finished:
                if self._start_revisit(t_ms, pose):
                    return self._step_recovery(t_ms, pose)
                self._enter(PHASE_LAND, t_ms)
                return self._step_land(t_ms, pose)
            goal = route.goal
        if self.phase == PHASE_RETURN_TO_PATH and route.waypoint_index > 0:
            if route.cross_track(pose) < self.params.return_tolerance_m:
                self._enter(PHASE_FOLLOW_PATH, t_ms)
        wx, wy = route.follow_velocity(pose, goal)
        return self._hover(*unrotate(pose.yaw_deg, wx, wy))

    # -- target selection and visual approach -------------------------------------------------------------

    def eligible_trees(self) -> list[StoredTree]:
        p = self.params
        return [t for t in self.memory.trees.values()
                if t.hits >= p.min_hits and self.route.in_planting_column(t.x, t.y)
                and not self.route.behind(t.x, t.y, t.first_ms)]

    def _select_target(self, t_ms, pose):
        candidates = self.eligible_trees()
        if not candidates:
            return False
        tree = nearest(candidates, self.camera.ground_point(pose))
        self.target_id = tree.id
        self.recovery.target_since = t_ms
        self.events.append(Event("target_selected", t_ms, tree.id, tree.x, tree.y))
        pose_capture = self._poses.at(tree.last_ms - self.params.cam_latency_ms) or pose
        if t_ms - tree.last_ms > self.params.lost_timeout_ms:
            # seen earlier but not in view now (e.g. during the climb): go to s_t by memory first; this is
            # the recovery manoeuvre, but not a lost target, so it is not counted as a recovery
            self._begin_recovery(t_ms, tree, 0.0, counted=False)
            return True
        u, v = self.camera.ego_corrected(Detection(tree.u, tree.v), pose_capture, pose)
        self._start_tracking(t_ms, u, v)
        return True

    def _start_tracking(self, t_ms, u, v):
        self.servo.start(t_ms, u, v)
        self.recovery.since = None
        self._enter(PHASE_APPROACH, t_ms)

    def _drop_target(self):
        self.target_id = 0
        self.servo.drop()

    def _step_approach(self, t_ms, pose):
        p = self.params
        tree = self.memory.get(self.target_id)
        if tree is None:  # evicted meanwhile: nothing left to approach
            self._drop_target()
            return self._after_tree(t_ms, pose)
        if self.recovery.target_expired(t_ms):
            return self._abandon(t_ms, pose, tree)
        self.servo.predict(t_ms)
        cx, cy = self.camera.ground_point(pose)
        e_d = math.hypot(tree.x - cx, tree.y - cy)
        if e_d > p.recovery_distance_m or t_ms - tree.last_ms > p.lost_timeout_ms:
            self._begin_recovery(t_ms, tree, e_d)
            return self._step_recovery(t_ms, pose)
        velocity = self.servo.step(t_ms, pose, self._last_tick)
        if velocity is None:
            return self._reached(t_ms, pose, tree)
        return self._hover(*velocity)

    def _reached(self, t_ms, pose, tree):
        cx, cy = self.camera.ground_point(pose)
        self.memory.mark_visited(tree.id, t_ms, (pose.x, pose.y), reached=True)
        self.counters.reached += 1
        self.events.append(Event("tree_reached", t_ms, tree.id, cx, cy,
                                 detail="s_t %.3f %.3f" % (tree.x, tree.y)))
        self._drop_target()
        self.route.note_reached(cx, cy, t_ms)
        self.route.reanchor(self._row_in_view(t_ms, (cx, cy)))
        return self._after_tree(t_ms, pose)

    def _row_in_view(self, t_ms, reached_at):
        """The row as the camera sees it now, over a reached tree (path_following, re-anchoring): the reached
        tree where the camera centres on it, then the column's trees that may be targets and were seen
        within ``lostTimeout`` (T_d order)."""
        return [reached_at] + [(t.x, t.y) for t in self.eligible_trees()
                               if t_ms - t.last_ms <= self.params.lost_timeout_ms]

    def _after_tree(self, t_ms, pose):
        """A target is done (reached, abandoned or evicted): back to the path, or, while going back for
        abandoned trees after the last waypoint, on to the next one or to landing."""
        if not self.recovery.revisiting:
            self._enter(PHASE_RETURN_TO_PATH, t_ms)
            return self._hover()
        self.recovery.revisiting = False
        if self._start_revisit(t_ms, pose):
            return self._hover()
        self._enter(PHASE_LAND, t_ms)
        return self._step_land(t_ms, pose)

    def _start_revisit(self, t_ms, pose):
        """Go back once for the nearest tree abandoned while hidden, by memory first. False if there is none."""
        tree = self.recovery.start_revisit(t_ms, self.memory, self.camera.ground_point(pose), (pose.x, pose.y),
                                           self.camera.centre, self.events)
        if tree is None:
            return False
        self.target_id = tree.id
        self._begin_recovery(t_ms, tree, 0.0, counted=False)
        return True

    # -- recovery -----------------------------------------------------------------------------------------

    def _begin_recovery(self, t_ms, tree, e_d, counted=True):
        self.counters.recoveries += int(counted)
        self.recovery.since = t_ms
        self.servo.lose()
        self.events.append(Event("recovery" if counted else "approach_by_memory", t_ms, tree.id, tree.x, tree.y,
                                 detail=self.recovery.reason(t_ms, tree, e_d)))
        self._enter(PHASE_RECOVERY, t_ms)

    def _abandon(self, t_ms, pose, tree, unseen=False):
        """Give the target up. ``unseen``: recovery timed out without seeing it again (hidden); such a tree is
        flagged for one more try before landing, unless this already was that try."""
        if tree is not None:
            revisit = unseen and not self.recovery.revisiting
            self.memory.mark_visited(tree.id, t_ms, (pose.x, pose.y), reached=False, revisit=revisit)
            self.counters.abandoned += 1
            self.events.append(Event("abandoned", t_ms, tree.id, tree.x, tree.y,
                                     detail="unseen: will go back once" if revisit else ""))
        self._drop_target()
        return self._after_tree(t_ms, pose)

    def _step_recovery(self, t_ms, pose):
        tree = self.memory.get(self.target_id)
        decision = self.recovery.step(t_ms, pose, tree, self.camera.ground_point(pose))
        if decision in (ABANDON, ABANDON_UNSEEN):
            return self._abandon(t_ms, pose, tree, unseen=decision == ABANDON_UNSEEN)
        return self._hover(*decision)
