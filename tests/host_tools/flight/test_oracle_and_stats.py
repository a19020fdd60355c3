"""The oracle camera and the flight statistics."""
import pytest

from crazyflie_app.app.navigation_core import NavigationCore, NavigationParams, Pose
from host_tools.flight.oracle import OracleCamera
from host_tools.flight.stats import mean_ci95, t_quantile_975
from host_tools.maps import load_map
from jevois_module.ForaNavTrees import foranav_serial as fs

ROUND_TRIP_TOLERANCE_M = 0.005  # standardized coordinates are integers: ~0.1 px


def test_that_oracle_pixels_map_back_to_the_tree_through_the_app_camera_model():
    pmap = load_map("map1")
    sut = OracleCamera(pmap, pixel_noise_px=0.0)
    core = NavigationCore(NavigationParams(), pmap.waypoints)
    pose = (1.2, 0.4, 1.25, 0.0)
    lines = sut.capture(0, pose)
    assert lines[-1] == "MARK STOP"
    seen = sut.visible(pose)
    assert [t.id for t, _, _ in seen] == [2]  # tree 1 and 3 are only partly in view
    msg = fs.parse_line(lines[0])
    u, v = fs.std_to_img_x(msg.x, 352), fs.std_to_img_y(msg.y, 288)
    x, y = core.pixel_to_world(u, v, Pose(1.2, 0.4, 1.25, 0.0, 0.0, 0.0))
    assert (x, y) == pytest.approx((1.32, 0.43), abs=ROUND_TRIP_TOLERANCE_M)


def test_that_the_oracle_reports_the_target_species_only_and_honours_hiding_and_dropout():
    pmap = load_map("map2")  # tree 4 is a coconut
    above_coconut = (2.33, 0.76, 1.25, 0.0)
    assert OracleCamera(pmap).capture(0, above_coconut) == ["MARK STOP"]
    above_tree_2 = (1.28, 0.62, 1.25, 0.0)  # tree 7 (an oil palm outside the column) is in view too
    assert len(OracleCamera(pmap).capture(0, above_tree_2)) == 3
    assert len(OracleCamera(pmap).capture(0, above_tree_2, hidden=frozenset([2]))) == 2
    assert OracleCamera(pmap).capture(0, above_tree_2, hidden=frozenset([2, 7])) == ["MARK STOP"]
    assert OracleCamera(pmap, dropout=1.0).capture(0, above_tree_2) == ["MARK STOP"]


def test_that_oracle_noise_is_seeded():
    pmap = load_map("map1")
    pose = (1.3, 0.45, 1.25, 0.0)
    a = [OracleCamera(pmap, seed=1).capture(t, pose) for t in range(5)]
    assert a == [OracleCamera(pmap, seed=1).capture(t, pose) for t in range(5)]
    assert a != [OracleCamera(pmap, seed=2).capture(t, pose) for t in range(5)]


def test_that_the_t_quantiles_match_the_tables():
    assert t_quantile_975(1) == pytest.approx(12.706)
    assert t_quantile_975(10) == pytest.approx(2.228)
    assert 2.042 > t_quantile_975(35) > 2.021
    assert t_quantile_975(10 ** 6) == pytest.approx(1.960, abs=0.001)


def test_that_the_ci_half_width_uses_the_t_distribution():
    mean, half = mean_ci95([1.0, 2.0, 3.0])
    assert mean == 2.0 and half == pytest.approx(4.303 / 3 ** 0.5)
    assert mean_ci95([0.5]) == (0.5, None)
    assert mean_ci95([]) == (None, None)
