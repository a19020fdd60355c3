"""The pure navigation core: camera model, column rule, servo law, reached rule, recovery, path phases.

A kinematic stand-in for the MAV (it moves exactly at the commanded velocity) and an ideal camera drive
the core tick by tick, so each behaviour is checked without the firmware emulation.
"""
import math

import pytest

from crazyflie_app.app import navigation_core as nc
from crazyflie_app.app.navigation_core import Detection, NavigationCore, NavigationParams, Pose, servo_velocity

ALTITUDE = 1.25
TICK_MS = 10
FRAME_MS = 100
PATH = ((0.0, 0.0), (4.0, 0.0))
DEVIATION_TOLERANCE_M = 0.03


class World(object):
    """The core + a kinematic MAV + an ideal camera (no noise, no latency) over a few trees."""

    def __init__(self, trees, path=PATH, start=(0.0, 0.0), **params):
        self.params = NavigationParams(cam_latency_ms=0, **params)
        self.core = NavigationCore(self.params, path)
        self.x, self.y = start
        self.vx = self.vy = 0.0
        self.wind = (0.0, 0.0)  # m/s added to the commanded velocity (a steady push the MAV does not feel)
        self.t = 0
        self.trees = list(trees)
        self.whole_crowns_m = None  # a crown size: the camera reports a tree only when that crown is whole in view
        self.hidden = set(range(len(self.trees)))  # nothing in view during the take-off
        self.commands = []
        self.core.start(0)
        self.run(1200)  # take-off settle at altitude
        assert self.core.phase == nc.PHASE_FOLLOW_PATH
        self.hidden = set()

    def pose(self):
        return Pose(self.x, self.y, self.params.altitude_m, 0.0, self.vx, self.vy)

    def pixel(self, tx, ty):
        f = self.params.focal_px
        return (self.params.cam_width_px / 2 - (ty - self.y) * f / self.params.altitude_m,
                self.params.cam_height_px / 2 - (tx - self.x) * f / self.params.altitude_m)

    def frame(self):
        dets = []
        px_per_m = self.params.focal_px / self.params.altitude_m
        r = 0.0 if self.whole_crowns_m is None else self.whole_crowns_m / 2 * px_per_m
        for i, (tx, ty) in enumerate(self.trees):
            u, v = self.pixel(tx, ty)
            if i not in self.hidden and r <= u <= 352 - r and r <= v <= 288 - r:
                dets.append(Detection(u, v))
        return dets

    def run(self, duration_ms, until=None):
        end = self.t + duration_ms
        while self.t < end:
            if self.t % FRAME_MS == 0:
                detections = self.frame()
                if detections:
                    self.core.on_frame(self.t, detections, self.pose())
            command = self.core.step(self.t, self.pose())
            self.commands.append((self.t, self.core.phase, command))
            self.vx, self.vy = (command.vx, command.vy) if command.kind == "hover" else (0.0, 0.0)
            self.vx += self.wind[0]
            self.vy += self.wind[1]
            self.x += self.vx * TICK_MS / 1000.0
            self.y += self.vy * TICK_MS / 1000.0
            self.t += TICK_MS
            if until is not None and until(self):
                return True
        return False

    def events(self, kind):
        return [e for e in self.core.events if e.kind == kind]


def test_that_pixels_map_to_the_ground_with_the_design_camera_model():
    core = NavigationCore(NavigationParams(), PATH)
    f = 1 / 0.0031
    pose = Pose(1.0, 2.0, ALTITUDE, 0.0, 0.0, 0.0)
    # 100 px above the centre is forward, 100 px left of the centre is left (DESIGN.md)
    assert core.pixel_to_world(176, 44, pose) == pytest.approx((1.0 + 100 * ALTITUDE / f, 2.0))
    assert core.pixel_to_world(76, 144, pose) == pytest.approx((1.0, 2.0 + 100 * ALTITUDE / f))
    turned = Pose(1.0, 2.0, ALTITUDE, 90.0, 0.0, 0.0)  # nose to +y: image up is world +y
    assert core.pixel_to_world(176, 44, turned) == pytest.approx((1.0, 2.0 + 100 * ALTITUDE / f))


def test_that_the_camera_mount_offset_moves_the_ground_point():
    core = NavigationCore(NavigationParams(cam_offset_x_m=0.2), PATH)
    assert core.pixel_to_world(176, 144, Pose(1.0, 0.0, ALTITUDE, 0.0, 0, 0)) == pytest.approx((1.2, 0.0))


def test_that_trees_outside_the_planting_column_are_ignored():
    # crown 0.35 m x 1.5 = 0.525 m: a tree 0.6 m off the path is outside, 0.3 m off is inside
    world = World([(0.3, 0.6), (0.3, -0.3)])
    world.core.on_frame(world.t, world.frame(), world.pose())
    stored = [(round(t.x, 2), round(t.y, 2)) for t in world.core.memory.trees.values()]
    assert stored == [(0.3, -0.3)]
    assert world.core.counters.out_of_column == 1


def test_that_the_column_rule_uses_the_current_segment():
    core = NavigationCore(NavigationParams(), ((0, 0), (4, 0), (4, -1), (0, -1)))
    core.waypoint_index = 1
    assert core.in_planting_column(2.0, 0.2) and not core.in_planting_column(2.0, -0.9)
    core.waypoint_index = 3
    assert core.in_planting_column(2.0, -0.9) and not core.in_planting_column(2.0, 0.2)


def test_that_a_tree_the_column_rule_left_out_does_not_pass_for_a_stored_neighbour():
    # moderate sweep flight 59, a turn segment: the target 0.40 m off the segment, the next column's first tree
    # 0.365 m beyond it (0.765 m off, never admitted). A frame that drops the target's own detection must not
    # hand the neighbour's detection to the target (its filter then never settled and it was abandoned)
    world = World([(0.3, -0.40), (0.3, -0.765)], start=(0.0, -0.3))  # both in view
    world.core.on_frame(world.t, world.frame(), world.pose())
    (target,) = world.core.memory.trees.values()
    stored_at = (target.x, target.y, target.hits)
    world.hidden = {0}
    assert world.core.on_frame(world.t + FRAME_MS, world.frame(), world.pose()) == [0]
    assert (target.x, target.y, target.hits) == stored_at
    assert world.core.counters.out_of_column == 2


def test_that_a_stored_tree_seen_just_outside_the_column_is_still_that_tree():
    # a crown 0.50 m off the path, its detection 0.54 m off (outside the 0.525 m column): the same tree
    world = World([(0.3, 0.50)])
    world.core.on_frame(world.t, world.frame(), world.pose())
    (tree,) = world.core.memory.trees.values()
    world.trees = [(0.3, 0.54)]
    assert world.core.on_frame(world.t + FRAME_MS, world.frame(), world.pose()) == [tree.id]
    assert tree.hits == 2


def test_that_the_servo_law_saturates_without_turning():
    vx, vy = servo_velocity(0.3, -0.4, gain=1.0, max_speed=0.1)
    assert math.hypot(vx, vy) == pytest.approx(0.1)
    assert vy / vx == pytest.approx(-0.4 / 0.3)
    assert servo_velocity(0.02, 0.0, gain=0.8, max_speed=0.1) == pytest.approx((0.016, 0.0))


def test_that_visual_servoing_approaches_the_tree_monotonically_and_stops_near_its_centre():
    world = World([(0.4, 0.12)])
    distances = []

    def watch(w):
        distances.append(math.hypot(0.4 - w.x, 0.12 - w.y))
        return bool(w.events("tree_reached"))

    assert world.run(20000, until=watch)
    approach = distances[next(i for i, (_, p, _) in enumerate(world.commands[-len(distances):])
                              if p == nc.PHASE_APPROACH):]
    assert all(b <= a + 1e-4 for a, b in zip(approach, approach[1:]))
    assert distances[-1] < DEVIATION_TOLERANCE_M


def test_that_a_tree_is_not_reached_at_the_40_px_capture_radius_alone():
    # with the paper's tau only, the tree would count as reached ~0.15 m off centre
    world = World([(0.4, 0.0)])
    reached_at = {}

    def watch(w):
        if w.events("tree_reached") and not reached_at:
            reached_at["d"] = math.hypot(0.4 - w.x, w.y)
        return bool(reached_at)

    world.run(20000, until=watch)
    px_per_m = world.params.focal_px / ALTITUDE
    assert reached_at["d"] * px_per_m < world.params.settle_radius_px + 1.0
    assert reached_at["d"] * px_per_m < world.params.capture_radius_px / 4


def test_that_one_detection_is_not_enough_to_pick_a_target():
    world = World([(0.3, 0.0)], min_hits=2)
    world.core.on_frame(world.t, world.frame(), world.pose())
    world.core.step(world.t, world.pose())
    assert world.core.phase == nc.PHASE_FOLLOW_PATH
    world.core.on_frame(world.t + 100, world.frame(), world.pose())
    world.core.step(world.t + 100, world.pose())
    assert world.core.phase == nc.PHASE_APPROACH


def test_that_a_lost_target_starts_recovery_and_a_new_detection_resumes_visual_guidance():
    world = World([(0.35, 0.1)])
    world.run(5000, until=lambda w: w.core.phase == nc.PHASE_APPROACH)
    world.hidden.add(0)
    assert world.run(2000, until=lambda w: w.core.phase == nc.PHASE_RECOVERY)
    assert world.core.counters.recoveries == 1
    world.hidden.clear()
    assert world.run(2000, until=lambda w: w.core.phase == nc.PHASE_APPROACH)
    assert world.events("reacquired")
    assert world.run(20000, until=lambda w: bool(w.events("tree_reached")))


def test_that_drifting_farther_than_delta_from_s_t_starts_recovery_and_returns_to_it():
    world = World([(0.35, 0.1)])
    world.run(5000, until=lambda w: w.core.phase == nc.PHASE_APPROACH)
    world.x -= 0.8  # a gust carries the MAV away: the tree is out of view and e_d > delta = 0.7 m
    world.run(20)
    assert world.core.phase == nc.PHASE_RECOVERY
    assert "e_d" in world.events("recovery")[0].detail
    # re-approach by position until the tree is seen again, then reach it visually
    assert world.run(30000, until=lambda w: bool(w.events("tree_reached")))
    assert math.hypot(0.35 - world.x, 0.1 - world.y) < DEVIATION_TOLERANCE_M


def test_that_a_tree_never_seen_again_is_abandoned_and_the_mission_goes_on():
    world = World([(0.35, 0.1)], recovery_timeout_ms=3000)
    world.run(5000, until=lambda w: w.core.phase == nc.PHASE_APPROACH)
    world.hidden.add(0)
    assert world.run(6000, until=lambda w: bool(w.events("abandoned")))
    assert world.core.phase == nc.PHASE_RETURN_TO_PATH
    assert [v.reached for v in world.core.memory.visited] == [False]
    assert world.core.counters.abandoned == 1


def test_that_return_to_path_runs_after_a_tree_and_ends_on_the_path():
    # the C app's return-to-path branch could never run
    world = World([(0.35, 0.2)], anchor_min_trees=1)
    assert world.run(20000, until=lambda w: bool(w.events("tree_reached")))
    assert world.core.phase == nc.PHASE_RETURN_TO_PATH
    assert world.run(20000, until=lambda w: w.core.phase == nc.PHASE_FOLLOW_PATH)
    # on the path as flown: the waypoints' line moved towards the reached tree (re-anchoring)
    assert world.core.route.cross_track(world.pose()) < world.params.return_tolerance_m
    assert 0.0 < world.core.route.offset[1] < 0.2


def test_that_the_target_survives_the_removal_of_another_tree():
    world = World([(0.35, 0.0)])
    other, _ = world.core.memory.add(0.0, 0.3, 0, 176, 144, (0, 0))
    world.run(5000, until=lambda w: w.core.phase == nc.PHASE_APPROACH)
    target = world.core.target_id
    world.core.memory.mark_visited(other, world.t, (world.x, world.y))
    world.run(100)
    assert world.core.target_id == target
    assert world.core.memory.get(target).x == pytest.approx(0.35, abs=0.02)


def test_that_an_evicted_target_sends_the_mav_back_to_the_path():
    world = World([(0.35, 0.0)])
    world.run(5000, until=lambda w: w.core.phase == nc.PHASE_APPROACH)
    world.core.memory.trees.pop(world.core.target_id)
    world.run(20)
    assert world.core.phase in (nc.PHASE_RETURN_TO_PATH, nc.PHASE_FOLLOW_PATH)
    assert world.core.target_id == 0


LANDED_HEIGHT_M = 0.01  # the last landing setpoint: at the ground


def test_that_the_last_waypoint_leads_to_landing_and_null_setpoints():
    world = World([], path=((0.0, 0.0), (0.3, 0.0)))
    assert world.run(20000, until=lambda w: w.core.phase == nc.PHASE_DONE)
    heights = [c.z for _, p, c in world.commands if p == nc.PHASE_LAND]
    final = [z for z in heights if z <= 0.15]
    # 0.5 m, then from landFinal (0.15 m) down to the ground: cutting the motors at 0.15 m drops the MAV at 1.7 m/s
    assert heights[0] == 0.5 and final[0] == 0.15
    assert final == sorted(final, reverse=True) and final[-1] < LANDED_HEIGHT_M
    assert world.core.step(world.t, world.pose()).kind == "null"


def test_that_a_tree_seen_earlier_but_out_of_view_is_approached_by_memory():
    # Fixture: a tree stored (2 hits) long ago (the take-off took longer than the lost timeout), not in view now
    world = World([], lost_timeout_ms=600)
    tree_id, _ = world.core.memory.add(0.9, 0.1, 0, 176, 144, (0, 0))
    world.core.memory.update(tree_id, 0.9, 0.1, 0, 176, 144)
    world.trees.append((0.9, 0.1))
    world.hidden.add(0)
    # Test
    world.run(20)
    # Assert: it flies to s_t by position (the recovery manoeuvre), not counted as a lost target
    assert world.core.phase == nc.PHASE_RECOVERY
    assert world.events("approach_by_memory") and world.core.counters.recoveries == 0
    world.hidden.clear()
    assert world.run(30000, until=lambda w: bool(w.events("tree_reached")))


STEADY_WIND = (0.0, 0.03)  # m/s sideways: the P law alone would hold the MAV ~3.8 cm (~10 px) off centre


def reached_after(world, limit_ms=60000):
    world.run(5000, until=lambda w: w.core.phase == nc.PHASE_APPROACH)
    start = world.t
    assert world.run(limit_ms, until=lambda w: bool(w.events("tree_reached")))
    return world.t - start, math.hypot(0.35 - world.x, 0.0 - world.y)


def test_that_the_servo_integral_cancels_a_steady_push():
    world = World([(0.35, 0.0)])
    world.wind = STEADY_WIND
    duration_ms, deviation = reached_after(world)
    assert duration_ms < world.params.settle_grace_ms  # no relaxation needed
    assert deviation < DEVIATION_TOLERANCE_M


def test_that_without_integral_the_relaxed_rule_still_finishes_the_tree():
    world = World([(0.35, 0.0)], servo_integral=0.0)
    world.wind = STEADY_WIND
    duration_ms, deviation = reached_after(world)
    assert duration_ms > world.params.settle_grace_ms
    assert deviation < 0.06  # the equilibrium offset, not the 0.15 m of tau alone


def test_that_a_waypoint_counts_as_passed_once_the_mav_is_beyond_its_segment_end():
    core = NavigationCore(NavigationParams(), ((0, 0), (4, 0), (4, -1)))
    end = 4.0 + core.route.end_reach_m  # the segment is flown that far beyond its end waypoint
    core.phase, core.waypoint_index = nc.PHASE_FOLLOW_PATH, 1
    core.step(0, Pose(end - 0.1, 0.1, ALTITUDE, 0.0, 0.1, 0.0))
    assert core.waypoint_index == 1
    core.step(10, Pose(end + 0.05, 0.1, ALTITUDE, 0.0, 0.1, 0.0))  # 0.11 m from the segment's end but past it
    assert core.waypoint_index == 2


@pytest.mark.parametrize("altitude, reach", [(0.9, 0.298), (1.0, 0.254), (1.25, 0.142), (1.6, 0.0)])
def test_that_a_segment_reaches_as_far_beyond_its_waypoint_as_the_column_is_out_of_whole_view(altitude, reach):
    # the column reaches 1.5 x 0.35 m beyond the waypoint; a 0.35 m crown is whole in the 288 px high frame up
    # to 144 px x height / 322.58 px - 0.175 m ahead
    core = NavigationCore(NavigationParams(altitude_m=altitude), ((0, 0), (2, 0), (2, 3)))
    assert core.route.end_reach_m == pytest.approx(reach, abs=1e-3)
    core.waypoint_index = 1
    assert core.route.segment_end() == pytest.approx((2.0 + core.route.end_reach_m, 0.0))


def test_that_the_last_tree_of_a_column_beyond_its_end_waypoint_is_reached():
    # issue 32 (tuning sweep 9 with trees beyond the column ends, flight 1): a palm 0.2 m beyond the last
    # waypoint, flown at 0.92 m, never came whole into view before the waypoint and the app landed (here 0.26 m)
    world = World([(2.26, 0.0)], path=((0.0, 0.0), (2.0, 0.0)), altitude_m=0.92)
    world.whole_crowns_m = 0.35  # the camera reports a crown only when it lies whole in the frame
    assert world.run(60000, until=lambda w: w.core.phase == nc.PHASE_DONE)
    assert len(world.events("tree_reached")) == 1


class DriftingWorld(World):
    """World whose state estimate drifts across the row as the MAV flies along it (the Flow deck alone):
    estimate y = true y + DRIFT_PER_M x true x. The camera sees the trees from the true pose."""

    def pose(self):
        return Pose(self.x, self.y + DRIFT_PER_M * self.x, self.params.altitude_m, 0.0, self.vx, self.vy)


DRIFT_PER_M = 0.3  # 0.9 m across the row after 3 m: every tree past ~1.8 m would leave the 0.525 m column
DRIFT_ROW = [(0.4 + 0.5 * i, 0.0) for i in range(7)]  # one row of 7 trees along the path, 0.5 m apart


def test_that_reanchoring_on_the_trees_follows_the_row_when_the_estimate_drifts():
    world = DriftingWorld(DRIFT_ROW, anchor_min_trees=1)
    world.run(300000, until=lambda w: w.core.phase == nc.PHASE_DONE)
    reached = world.events("tree_reached")
    assert len(reached) == len(DRIFT_ROW)
    # the flown line moved with the drift (estimate frame): towards +y, most of the 0.3 m/m x 3.4 m
    assert world.core.route.offset[1] > 0.5


def test_that_without_reanchoring_the_drifted_estimate_loses_the_row():
    # the same flight with re-anchoring off (app.anchorMin 0): the trees leave the column; this is what the
    # feature fixes, and shows the scenario above can fail
    world = DriftingWorld(DRIFT_ROW, anchor_min_trees=0)
    world.run(300000, until=lambda w: w.core.phase == nc.PHASE_DONE)
    assert len(world.events("tree_reached")) < len(DRIFT_ROW) - 2


def test_that_a_tree_first_seen_behind_the_last_reached_one_is_not_a_target():
    core = NavigationCore(NavigationParams(), PATH)
    core.route.note_reached(2.0, 0.0, 5000)
    seen_after = 5100
    assert core.route.behind(1.4, 0.0, seen_after)
    assert not core.route.behind(1.7, 0.0, seen_after) and not core.route.behind(2.5, 0.0, seen_after)
    core.route.advance()  # 0 -> 1: still the first row
    assert core.route.behind(1.4, 0.0, seen_after)


def test_that_a_tree_seen_before_the_reach_and_passed_stays_a_target():
    # flight 91 of sweep seed 1100: a palm before the first waypoint, seen on the way in, passed when the next
    # palm was reached first; it must still be gone back for
    core = NavigationCore(NavigationParams(), PATH)
    core.route.note_reached(2.0, 0.0, 5000)
    assert not core.route.behind(1.4, 0.0, 4000)


def test_that_the_first_waypoint_is_passed_from_inside_the_first_row():
    core = NavigationCore(NavigationParams(), PATH)
    assert core.route.waypoint_reached(Pose(0.8, 0.1, ALTITUDE, 0.0, 0.0, 0.0))  # in the row, past (0, 0)
    assert not core.route.waypoint_reached(Pose(-0.5, 0.0, ALTITUDE, 0.0, 0.0, 0.0))  # before it
    assert not core.route.waypoint_reached(Pose(0.8, 0.9, ALTITUDE, 0.0, 0.0, 0.0))  # beside the row


def test_that_the_row_spacing_caps_the_planting_column():
    # rows 0.6 m apart: the paper's 0.525 m column would take in the next row's trees at 0.6 m with 0.1 m
    # jitter; half the spacing keeps each tree with its nearest row
    plain = NavigationCore(NavigationParams(), PATH)
    spaced = NavigationCore(NavigationParams(row_spacing_m=0.6), PATH)
    assert plain.in_planting_column(1.0, 0.5) and not spaced.in_planting_column(1.0, 0.5)
    assert spaced.in_planting_column(1.0, 0.25)
    wide = NavigationCore(NavigationParams(row_spacing_m=4.0), PATH)  # wide rows: the paper's rule holds
    assert wide.in_planting_column(1.0, 0.5) and not wide.in_planting_column(1.0, 0.6)
