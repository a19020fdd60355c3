"""Stock cflib writes nonsense into app params of a running flight: a zero camera width and a NaN cruise speed
are refused, the echo carries the kept value, and the mission reaches its trees as it would have (before, the
zero width flew every target blind and exited 0, the NaN speed stalled the mission)."""
import math

import pytest

from tests.crazyflie_app.firmware.crtp.conftest import Session, wait_for

FLIGHT_S = 30.0
FIRST_TREES = [1, 2]  # map 1's oracle flight reaches them by 25 s (tests/host_tools/flight: 14.6 s, 24.6 s)


def test_that_cflib_writes_outside_the_valid_range_are_refused_and_the_mission_flies_on(flight_process, tmp_path):
    # Fixture: map 1, lockstep, oracle camera, served over CRTP
    child = flight_process(options={"crtp": "127.0.0.1:0", "max_time_s": FLIGHT_S})
    session = Session(child.uri, tmp_path / "toc_cache")
    assert session.first_sent.wait(10)
    child.go()
    session.wait()
    cf = session.cf
    echoes = {}
    for name in ("camWidth", "cruiseSpeed"):
        cf.param.add_update_callback(group="app", name=name,
                                     cb=lambda full, value: echoes.setdefault(full, []).append(value))
    # Test: the slips of the issue, through cflib's ordinary param.set_value
    cf.param.set_value("app.camWidth", 0)
    cf.param.set_value("app.cruiseSpeed", math.nan)
    wait_for(lambda: len(echoes) == 2, what="both echoes")
    session.close()
    result = child.finish()
    # Assert: each echo is the value kept (the defaults), the flight reached its first trees
    assert int(echoes["app.camWidth"][-1]) == 352
    assert float(echoes["app.cruiseSpeed"][-1]) == pytest.approx(0.10)
    assert result["stats"] is not None
    reached = [tree["id"] for tree in result["summary"]["reached"]]
    assert reached[:2] == FIRST_TREES
