"""The flight app under faults (issue #11 items 1, 2, 10, 11; issue #12 item 7): a camera never heard keeps the
MAV on the ground, frames with more detections than T_d has room for never crash, a frame without MARK STOP
cannot grow without limit, a tree abandoned while hidden gets one more try before landing, and one crown seen
twice in one frame is one tree."""
import dataclasses
import json
import subprocess
import sys

import pytest

from crazyflie_app.firmware import COMMANDER_PRIORITY_DISABLE, Crazyflie, v_task_delay
from crazyflie_app.app.navigation import BOOT_DELAY_MS, PRE_TAKEOFF_DELAY_MS, NavigationApp
from crazyflie_app.app.navigation_core import (PHASE_FOLLOW_PATH, PHASE_LAND, PHASE_NO_CAMERA,
                                           PHASE_RECOVERY, PHASE_TAKEOFF, Detection, NavigationCore,
                                           NavigationParams, Pose, merge_duplicates)
from crazyflie_app.app.tree_memory import TreeMemory
from host_tools.errors import ForaNavError
from host_tools.flight import camera_factory, run_flight
from host_tools.maps import load_map
from jevois_module.ForaNavTrees import foranav_serial as fs
from tests.conftest import FIXTURES

from tests.crazyflie_app.conftest import console_text

PATH = ((0.0, 0.0), (3.0, 0.0))
BOOTED_MS = BOOT_DELAY_MS + 10
AIRBORNE_M = 0.1  # above this the MAV has left the ground
FRAME_MS = 111
FAULT_MAPS = FIXTURES / "faults"  # maps of docs/faults.md


def make_app(**params):
    cf = Crazyflie(seed=1)
    app = NavigationApp(cf, PATH, "loop://")
    for name, value in params.items():
        cf.registry.param_set("app." + name, value)
    app.start()
    return cf, app


def camera_task(app, frame_lines, period_ms=FRAME_MS):
    """A camera on the loop port: ``frame_lines(k)`` -> bytes of frame k, every ``period_ms``."""
    k = 0
    while True:
        if app.link.port is not None:
            app.link.port.write(frame_lines(k))
            k += 1
        yield v_task_delay(period_ms)


def t2_frame(pixels):
    return b"MARK START\r\n" + b"".join(fs.format_t2(u, v, 352, 288).encode() + b"\r\n" for u, v in pixels) \
        + b"MARK STOP\r\n"


# -- 1. a camera never heard is a camera lost ---------------------------------------------------------------

def test_that_a_camera_never_heard_keeps_the_mav_on_the_ground_with_a_console_line():
    # Fixture: the app on a port nobody writes to
    cf, app = make_app()
    # Test
    cf.run_until(BOOT_DELAY_MS + PRE_TAKEOFF_DELAY_MS + app.params.camera_wait_ms + 5000)
    # Assert: never took off, said why, parked
    assert app.phase == PHASE_NO_CAMERA
    assert cf.model.truth.z < AIRBORNE_M
    assert cf.commander.commander_get_active_priority() == COMMANDER_PRIORITY_DISABLE  # never commanded
    assert "No camera heard for 20.0 s, not taking off" in console_text(cf)
    assert "APP" not in cf.scheduler.task_names()


def test_that_the_app_waits_for_a_late_camera_then_takes_off():
    cf, app = make_app()
    late_ms = BOOT_DELAY_MS + PRE_TAKEOFF_DELAY_MS + 4000
    cf.run_until(late_ms)
    assert app.phase not in (PHASE_TAKEOFF, PHASE_NO_CAMERA) and "Waiting for the camera" in console_text(cf)
    cf.x_task_create(camera_task(app, lambda k: t2_frame([])), "TEST_CAMERA", 6)
    cf.run_until(late_ms + 500)
    assert app.phase == PHASE_TAKEOFF


def test_that_a_camera_heard_only_long_before_take_off_does_not_count():
    # heard once during boot, then silent: at the take-off check it is not alive
    cf, app = make_app(camWaitMs=3000)
    cf.run_until(BOOTED_MS)
    app.link.port.write(t2_frame([]))
    cf.run_until(BOOT_DELAY_MS + PRE_TAKEOFF_DELAY_MS + 4000)
    assert app.last_heard_ms > 0 and app.phase == PHASE_NO_CAMERA


def test_that_fly_with_a_camera_silent_from_power_on_does_not_take_off_and_exits_1(tmp_path):
    # the command: today it flew the whole path blind, reached 0 of 6, printed "completed", exit 0
    result = subprocess.run([sys.executable, "-m", "host_tools.cli", "fly", "--map", "map1", "--camera", "oracle",
                             "--silence", "0:100000", "--json", "--out", str(tmp_path)],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 1, result.stderr
    summary = json.loads(result.stdout)
    assert summary["camera_never_heard"] and not summary["completed"] and not summary["success"]
    assert summary["reached"] == []


def test_that_the_table_says_the_camera_was_never_heard():
    import io

    from host_tools.flight.cmd_fly import print_table

    summary = run_flight(load_map("map1"), camera_factory("oracle")(load_map("map1")),
                         options={"silence": [(0.0, 1000.0)]})
    out = io.StringIO()
    print_table(summary, out)
    assert "NOT STARTED: camera never heard" in out.getvalue().splitlines()[0]


# -- 2. more detections in one frame than T_d has room for -----------------------------------------------------

def flood_app(lines_per_frame, frames, **params):
    """The app at flight height with a camera sending ``lines_per_frame`` detections spread over the image."""
    cf, app = make_app(**params)

    def frame(k):  # distinct pixels, all inside the planting column of the path
        pixels = [(45 + (37 * i + 11 * k) % 260, (53 * i + 7 * k) % 288) for i in range(lines_per_frame)]
        return t2_frame(pixels)

    cf.x_task_create(camera_task(app, frame), "TEST_CAMERA", 6)
    cf.run_until(BOOT_DELAY_MS + PRE_TAKEOFF_DELAY_MS + frames * FRAME_MS)
    return cf, app


@pytest.mark.parametrize("lines_per_frame, params", [
    (33, {"dupRadius": 0.0}), (5, {"treeCapacity": 8, "dupRadius": 0.0}), (40, {"treeCapacity": 1, "dupRadius": 0.0}),
    (33, {}), (5, {"treeCapacity": 8})])
def test_that_a_frame_with_more_detections_than_the_memory_holds_never_crashes(lines_per_frame, params):
    # the cases (KeyError: a new tree evicted one that a later detection of the frame referred to);
    # dupRadius 0: every line of a frame is a distinct tree, so the overflow path surely runs
    cf, app = flood_app(lines_per_frame, 120, **params)
    capacity = params.get("treeCapacity", 32)
    assert app.frames >= 100  # the app kept taking frames (a KeyError would have killed the camera task)
    assert app.num_trees <= capacity
    if params.get("dupRadius") == 0.0:
        assert app.core.memory.evicted > 0  # the overflow path really ran
        assert (app.core.memory.unstored > 0) == (lines_per_frame > capacity)  # more lines than room: unstored


def test_that_eviction_spares_the_trees_of_the_same_frame():
    sut = TreeMemory(capacity=2)
    near, far = sut.add(0.0, 0.0, 0, 0, 0, (0, 0))[0], sut.add(5.0, 0.0, 0, 0, 0, (0, 0))[0]
    # the far tree was seen in this frame: the new one evicts the near one, not the far one
    new, evicted = sut.add(1.0, 0.0, 10, 0, 0, (0, 0), protected={far})
    assert evicted == [near] and set(sut.trees) == {far, new}
    # every stored tree seen in this frame: the new tree is not stored, and that is counted
    assert sut.add(2.0, 0.0, 10, 0, 0, (0, 0), protected={far, new}) == (0, [])
    assert sut.unstored == 1 and set(sut.trees) == {far, new}


def test_that_a_dense_plantation_with_the_oracle_never_crashes():
    # a grid of small palms every 0.15 m over the columns: ~60 in view at once, T_d holds 32 (KeyError before)
    pmap = load_map(str(FAULT_MAPS / "dense_0p15m.json"))
    summary = run_flight(pmap, camera_factory("oracle")(pmap), options={"max_time_s": 60})
    assert summary["detections"] > 5000  # it flew and kept taking the flood


def test_that_a_map_flown_at_1000_m_with_the_oracle_never_crashes():
    # the loader refuses such a map now (host_tools.maps.ALTITUDE_RANGE_M); the app must still survive every
    # tree of the map in one frame, so the map is built past the loader
    with pytest.raises(ForaNavError, match="altitude_m: must be from"):
        load_map(str(FAULT_MAPS / "map1_1000m.json"))
    pmap = dataclasses.replace(load_map("map1"), altitude_m=1000.0)
    summary = run_flight(pmap, camera_factory("oracle")(pmap), options={"max_time_s": 60})
    assert summary["detections"] > 0


# -- 10. a frame that never ends is bounded -----------------------------------------------------------------

def test_that_t2_lines_without_mark_stop_do_not_pile_up():
    cf, app = make_app()
    # 300 lines per 10 ms (loop:// holds 4 KiB): 60,000 T2 lines after one MARK STOP, none since
    cf.x_task_create(camera_task(app, lambda k: t2_frame([]) if k == 0 else b"T2 10 20\r\n" * 300, 10),
                     "TEST_CAMERA", 6)
    cf.run_until(2000)
    assert app.frame_overflow > 50000
    assert app.pending_detections == app.params.frame_capacity


def test_that_lowering_frame_cap_in_flight_trims_the_pending_frame():
    # found by the fuzz run: app.frameCap lowered while a long frame was pending left it above the cap
    cf, app = make_app()
    cf.run_until(BOOTED_MS)
    app.link.port.write(t2_frame([]) + b"T2 10 20\r\n" * 50)
    cf.run_until(BOOTED_MS + 20)
    assert app.pending_detections == 50
    cf.registry.param_set("app.frameCap", 10)
    cf.run_until(BOOTED_MS + 40)
    assert app.pending_detections == 10 and app.frame_overflow == 40


# -- 11. go back once for a tree abandoned while hidden ------------------------------------------------------

def test_that_a_tree_hidden_for_20_s_is_reached_on_the_way_back_before_landing():
    # today: abandoned, never revisited, 5 of 6 reached
    pmap = load_map("map1")
    summary = run_flight(pmap, camera_factory("oracle")(pmap), options={"hide_tree": 3, "hide_s": 20.0})
    assert summary["abandoned"] == 1
    assert summary["missed_targets"] == [] and summary["repeated_targets"] == [] and summary["success"]
    assert summary["reached"][-1]["id"] == 3  # reached last: after the path, before landing


def test_that_a_tree_hidden_for_good_is_tried_once_more_and_then_the_mav_lands():
    pmap = load_map("map1")
    summary = run_flight(pmap, camera_factory("oracle")(pmap), options={"hide_tree": 3, "hide_s": 10000.0})
    assert summary["abandoned"] == 2  # once in the column, once on the way back: never a third time
    assert summary["missed_targets"] == [3] and summary["completed"]


def _flying_core(**params):
    core = NavigationCore(NavigationParams(cam_latency_ms=0, **params), PATH)
    core.start(0)
    t = 0
    pose = Pose(0.0, 0.0, 1.25, 0.0, 0.0, 0.0)
    while core.phase != PHASE_FOLLOW_PATH:
        t += 10
        core.step(t, pose)
    return core, t, pose


def test_that_a_tree_abandoned_for_a_timeout_while_seen_is_not_revisited():
    # abandoned by app.targetTimeout (seen, never settled) is not "abandoned while hidden"
    core, t, pose = _flying_core(target_timeout_ms=2000)
    for k in range(3):
        core.on_frame(t + 100 * k, [Detection(176, 44)], pose)  # 0.39 m ahead, in the column
    t += 300
    while core.counters.abandoned == 0:
        t += 10
        core.on_frame(t, [Detection(176, 44)], pose)  # keeps seeing it: no recovery timeout
        core.step(t, pose)
        assert t < 10000
    assert [e.revisit for e in core.memory.visited] == [False]


def test_that_the_revisit_goes_to_the_tree_and_its_timeout_starts_there():
    core, t, pose = _flying_core(recovery_timeout_ms=3000)
    core.on_frame(t, [Detection(176, 44)], pose)
    core.on_frame(t + 100, [Detection(176, 44)], pose)
    t += 100
    x = 0.0
    while not core.memory.visited:  # never seen again: recovery, then abandoned, flagged
        t += 10
        command = core.step(t, Pose(x, 0.0, 1.25, 0.0, 0.0, 0.0))
        x += command.vx * 0.01
    assert core.memory.visited[0].revisit
    stored = core.memory.visited[0]
    while core.phase != PHASE_RECOVERY or not core.revisiting:  # fly on to the end of the path
        t += 10
        command = core.step(t, Pose(x, 0.0, 1.25, 0.0, 0.0, 0.0))
        x += command.vx * 0.01
        assert t < 200000
    assert core.target_id == stored.id and x > 2.9  # at the end, going back for it
    while core.phase == PHASE_RECOVERY:
        t += 10
        command = core.step(t, Pose(x, 0.0, 1.25, 0.0, 0.0, 0.0))
        x += command.vx * 0.01
    assert abs(x - stored.x) < 0.06  # it got there before its recovery clock ran out (3 s, 26 s of flight)
    assert core.phase == PHASE_LAND and not core.memory.visited[-1].revisit


def test_that_an_abandoned_tree_next_to_a_reached_one_is_not_gone_back_for():
    # sweep flight m7 (flow estimator): one crown stored twice 0.15 m apart, one copy abandoned unseen, the
    # other reached; going back for the abandoned copy reached the same tree a second time
    core, t, pose = _flying_core()
    abandoned, _ = core.memory.add(1.265, 5.0, t, 176.0, 144.0, (0.0, 0.0))
    core.memory.mark_visited(abandoned, t, (0.0, 0.0), reached=False, revisit=True)
    reached, _ = core.memory.add(1.175, 5.12, t, 176.0, 144.0, (0.0, 0.0))
    core.memory.mark_visited(reached, t, (0.0, 0.0), reached=True)
    x = 0.0
    while core.phase not in (PHASE_LAND,):
        t += 10
        command = core.step(t, Pose(x, 0.0, 1.25, 0.0, 0.0, 0.0))
        x += command.vx * 0.01
        assert t < 200000
    assert not core.revisiting and [e.kind for e in core.events].count("revisit") == 0


# -- #12.7: one crown seen twice in one frame is one tree -----------------------------------------------------

def test_that_two_detections_of_one_crown_in_one_frame_are_merged():
    # Map 1 at 1.0 m, seed 0, --camera sim: the module sent these two for Tree 1 (0.15 m apart)
    kept, owner = merge_duplicates([Detection(198.5, 77.6), Detection(150.8, 86.2)],
                                   [(0.795, 0.367), (0.769, 0.515)], 0.25)
    assert owner == [0, 0] and len(kept) == 1
    assert kept[0][1] == pytest.approx((0.782, 0.441))


def test_that_a_frame_with_a_duplicate_stores_one_tree_and_a_cluster_pair_two():
    core, t, pose = _flying_core()
    ids = core.on_frame(t, [Detection(198.5, 77.6), Detection(150.8, 86.2)], pose)  # 0.15 m apart
    assert ids[0] == ids[1] != 0 and len(core.memory) == 1 and core.counters.duplicates == 1
    core2, t2, pose2 = _flying_core()
    ids = core2.on_frame(t2, [Detection(176, 204), Detection(176, 204 - 0.47 * 322.58 / 1.25)], pose2)
    assert ids[0] != ids[1] and len(core2.memory) == 2  # a cluster: crowns touching, 0.47 m apart


@pytest.mark.slow
def test_that_map1_at_1_m_with_the_vision_camera_reaches_each_tree_once():
    # the double reach of issue #12: tree 1 reached twice (two T_d entries from one frame's two windows)
    pmap = load_map(str(FAULT_MAPS / "map1_1m.json"))
    summary = run_flight(pmap, camera_factory("sim")(pmap, seed=0), seed=0)
    assert summary["repeated_targets"] == [] and summary["success"]
