"""A client may write any value into an app PARAM (cfclient or cflib over --crtp, a flight option): a write
outside the PARAM table's valid range, or NaN, is refused and the param keeps its value, so a slip never flies
the mission blind (a zero camera width) or stalls it (a NaN speed). Over CRTP: tests/crazyflie_app/firmware/
crtp/test_app_param_checks.py."""
import math

import pytest

from crazyflie_app.app.navigation import PARAM_TABLE
from crazyflie_app.firmware import Crazyflie
from crazyflie_app.firmware.logparam import ParamRangeError
from host_tools.errors import ForaNavError
from host_tools.flight import OracleCamera, run_flight
from host_tools.flight.registry import app_factory
from host_tools.maps import load_map

PATH = [(0.0, 0.0), (2.0, 0.0)]


@pytest.mark.parametrize("app", ["python", "c"])
@pytest.mark.parametrize("name, value", [("app.camWidth", 0), ("app.camScale", 0.0), ("app.cruiseSpeed", math.nan),
                                         ("app.altitude", math.inf), ("app.frameCap", 0)])
def test_that_a_write_outside_the_valid_range_is_refused_and_the_value_kept(app, name, value):
    # Fixture
    cf = Crazyflie(seed=0)
    cf.attach_uart2("loop://")
    app_factory(app)(cf, PATH, "oil_palm")
    before = cf.registry.param_read(name)
    # Test / Assert: refused, named, the param unchanged
    with pytest.raises(ParamRangeError, match=name.replace(".", r"\.")):
        cf.registry.param_set(name, value)
    assert cf.registry.param_read(name) == before
    cf.close()


def test_that_every_app_param_has_a_valid_range_holding_its_default():
    cf = Crazyflie(seed=0)
    cf.attach_uart2("loop://")
    app_factory("python")(cf, PATH, "oil_palm")
    for entry in PARAM_TABLE.entries:
        low, high = entry.valid
        assert low <= cf.registry.param_read("app." + entry.name) <= high, entry.name
    cf.close()


def test_that_a_flight_option_outside_the_range_is_a_user_error_naming_it():
    pmap = load_map("map1")
    options = {"max_time_s": 5.0, "params": {"app.camWidth": 0}}
    with pytest.raises(ForaNavError, match=r"params: param app\.camWidth: 0 refused, valid 16\.\.4096 px"):
        run_flight(pmap, OracleCamera(pmap, seed=0), seed=0, options=options)
