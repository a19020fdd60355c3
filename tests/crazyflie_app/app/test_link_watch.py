"""The app's behaviour with a real camera in the loop (pure core): hold position when the camera goes silent
in flight, resume when frames come back, land when it stays silent, never judge a camera that sends no frame
marks; and give a target up after app.targetTimeout so a flickering detection cannot stall the mission."""
from crazyflie_app.app.navigation_core import (PHASE_FOLLOW_PATH, PHASE_LAND, PHASE_RETURN_TO_PATH, Detection,
                                           NavigationCore, NavigationParams, Pose)

PATH = [(0.0, 0.0), (5.0, 0.0)]
AT_ALTITUDE = Pose(0.0, 0.0, 1.25, 0.0, 0.0, 0.0)  # at the first waypoint: the path goes +x


def _flying_core():
    core = NavigationCore(NavigationParams(), PATH)
    core.start(0)
    t = 0
    while core.phase != PHASE_FOLLOW_PATH:  # take off: the pose is already at altitude
        t += 10
        core.step(t, AT_ALTITUDE)
    return core, t


def test_that_a_silent_link_holds_position_then_resumes():
    core, t = _flying_core()
    core.on_frame_mark(t)
    p = core.params
    moving = core.step(t + 10, AT_ALTITUDE)
    held = core.step(t + p.link_hold_ms + 10, AT_ALTITUDE)
    assert moving.vx > 0  # following the path
    assert (held.kind, held.vx, held.vy, held.z) == ("hover", 0.0, 0.0, p.altitude_m)
    assert core.link_lost and core.counters.link_losses == 1 and core.phase == PHASE_FOLLOW_PATH
    core.on_frame_mark(t + p.link_hold_ms + 50)
    resumed = core.step(t + p.link_hold_ms + 60, AT_ALTITUDE)
    assert resumed.vx > 0 and not core.link_lost and not core.link_aborted
    assert [e.kind for e in core.events if e.kind.startswith("link")] == ["link_lost", "link_restored"]


def test_that_a_dead_link_lands():
    core, t = _flying_core()
    core.on_frame_mark(t)
    command = core.step(t + core.params.link_land_ms + 10, AT_ALTITUDE)
    assert core.phase == PHASE_LAND and core.link_aborted
    assert command.kind == "hover" and command.z == core.params.land_height_m and command.vx == 0.0


def test_that_a_camera_without_frame_marks_is_not_watched():
    core, t = _flying_core()
    command = core.step(t + 60000, AT_ALTITUDE)  # a minute without any mark: nothing to judge the link by
    assert not core.link_lost and core.phase != PHASE_LAND and command.vx > 0


def test_that_a_target_never_reached_is_abandoned_after_the_target_timeout():
    # Fixture: recovery alone would never give up; the target budget is 5 s
    core = NavigationCore(NavigationParams(recovery_timeout_ms=600000, target_timeout_ms=5000), PATH)
    core.start(0)
    t = 0
    while core.phase != PHASE_FOLLOW_PATH:
        t += 10
        core.step(t, AT_ALTITUDE)
    for _ in range(3):  # a tree just ahead, seen in three frames, then never again
        t += 111
        core.on_frame(t, [Detection(176.0, 100.0)], AT_ALTITUDE)
        core.step(t, AT_ALTITUDE)
    assert core.target_id != 0
    selected = [e.t_ms for e in core.events if e.kind == "target_selected"][-1]
    # Test
    while core.target_id != 0 and t < selected + 20000:
        t += 10
        core.step(t, AT_ALTITUDE)
    # Assert: given up at the budget, not before, and the mission goes on
    kinds = [e.kind for e in core.events]
    assert "abandoned" in kinds and core.counters.abandoned == 1
    assert selected + 5000 < t <= selected + 5000 + 20
    assert core.phase == PHASE_RETURN_TO_PATH
