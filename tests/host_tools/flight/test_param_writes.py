"""A client may write any value into an app PARAM (cfclient over --crtp): nonsense gives a wrong flight, never
a crash of either app."""
import pytest

from host_tools.flight import OracleCamera, run_flight
from host_tools.maps import load_map


@pytest.mark.parametrize("app", ["python", "c"])
def test_that_zero_camera_geometry_gives_a_wrong_flight_not_a_crash(app):
    # Fixture: app.camScale and app.camWidth written as 0 (a slip in cfclient's Parameters tab)
    pmap = load_map("map1")
    options = {"app": app, "max_time_s": 40.0, "params": {"app.camScale": 0.0, "app.camWidth": 0}}
    # Test
    summary = run_flight(pmap, OracleCamera(pmap, seed=0), seed=0, options=options)
    # Assert: the flight ran to its time limit (no ZeroDivisionError in the app, no inf in the C core's setpoints)
    assert summary["mission_time_s"] > 30 and summary["watchdog_events"] == 0
