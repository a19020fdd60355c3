"""--realtime: camera and flight as two processes sharing only the pty, on the (sped-up) wall clock."""
import pytest

from host_tools.errors import ForaNavError
from host_tools.flight.realtime import run_realtime
from host_tools.maps import load_map

SPEED = 8.0  # Map 1 (~115 s simulated) in ~15 s of wall clock; the camera process still keeps up
HOLD_RADIUS_M = 0.25  # 1 s of silence at <= 0.1 m/s before the hold starts, braking, then drift while landing
KILL_AT_S = 20.0


def test_that_realtime_completes_map1():
    summary = run_realtime(load_map("map1"), speed=SPEED, options={"max_time_s": 400})
    assert summary["completed"] and summary["watchdog_events"] == 0
    assert summary["vision"]["frames"] > 0 and summary["detections"] > 0  # lines crossed the pty
    assert len(summary["reached"]) >= 3  # the app found trees from the other process's detections
    assert summary["realtime"]["camera_killed_at_s"] is None


def test_that_when_the_camera_process_dies_the_app_holds_and_lands():
    summary = run_realtime(load_map("map1"), speed=SPEED, options={"max_time_s": 80}, kill_camera_at_s=KILL_AT_S)
    after = summary["after_camera_loss"]
    assert summary["realtime"]["camera_killed_at_s"] == KILL_AT_S
    assert summary["link_aborted"] and not summary["completed"]  # landed on purpose, mission not done
    assert after["landed"] and after["final_height_m"] < 0.05
    assert after["max_distance_m"] < HOLD_RADIUS_M  # did not fly away
    assert summary["watchdog_events"] == 0


def test_that_lockstep_only_faults_are_refused_in_realtime():
    with pytest.raises(ForaNavError, match="garbage_rate"):
        run_realtime(load_map("map1"), speed=SPEED, options={"garbage_rate": 0.1})
