"""The harness as a function: plain data in, summary out, picklable, the app a pluggable component."""
import pickle

import pytest

from host_tools.errors import ForaNavError
from host_tools.flight import harness
from host_tools.maps import load_map, map_to_dict
from crazyflie_app.app.navigation import NavigationApp
from crazyflie_app.app.uart2_link import Uart2Link


def test_that_fly_pickles_by_reference_and_flies_plain_data():
    # Fixture: what a Dask task ships
    fn = pickle.loads(pickle.dumps(harness.fly))
    data = pickle.loads(pickle.dumps(map_to_dict(load_map("map1"))))
    # Test
    summary = fn(data, camera="oracle", seed=3)
    # Assert
    assert fn is harness.fly
    assert summary["success"] and summary["targets"] == [t.id for t in load_map("map1").targets]


def test_that_the_app_is_a_component_chosen_by_name():
    # Fixture: a registered app factory that records that it was used
    built = []

    def recording_app(cf, waypoints, target_label):
        built.append(target_label)
        return NavigationApp(cf, waypoints, None, link=Uart2Link(cf), target_label=target_label)

    harness.register_app("recording", recording_app)
    data = map_to_dict(load_map("map2"))
    # Test
    summary = harness.fly(data, camera="oracle", app="recording", seed=1)
    # Assert
    assert built == ["oil_palm"]
    default = harness.fly(data, camera="oracle", seed=1)  # app="python"
    assert len(built) == 1  # the default app is not the recording one
    summary.pop("cpu_s")
    default.pop("cpu_s")
    assert summary == default


def test_that_an_unknown_app_fails_in_one_line():
    with pytest.raises(ForaNavError, match="app"):
        harness.fly(map_to_dict(load_map("map1")), camera="oracle", app="no_such_app")
