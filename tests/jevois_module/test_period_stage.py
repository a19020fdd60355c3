"""The opt-in period-tied peak stage (foranav_period, grouping.group_by_centre, DetectorSettings.grouping)."""
import numpy as np
import pytest

import host_tools.detection  # noqa: F401  (puts the camera module's folder on the path)
import foranav_detector as detector_core
import foranav_features as features
import foranav_model
import foranav_period as period
from host_tools.detection import period_pairs, synthetic
from host_tools.jevois_host import ModuleRunner
from tests.conftest import REPO_ROOT

SHIPPED_MODEL = REPO_ROOT / "jevois_module" / "ForaNavTrees" / "foranav_oil_palm.npz"
PERIOD_TOLERANCE = 0.05  # of the true period, on a synthetic grid of crowns


def _grid_frame(spacing, crown_share, seed=0, height=288, width=352):
    """Synthetic palms on a square grid of `spacing` px, crowns `crown_share` x spacing across."""
    rng = np.random.RandomState(seed)
    image = synthetic.ground(rng, height, width)
    for y in np.arange(spacing / 3.0, height + spacing, spacing):
        for x in np.arange(spacing / 4.0, width + spacing, spacing):
            synthetic.draw_palm(image, rng, x, y, spacing * crown_share)
    return features.bgr_to_hsv(image)[:, :, 2].copy()


@pytest.mark.parametrize("spacing", [70, 90, 110, 130])
@pytest.mark.parametrize("crown_share", [0.8, 1.0])
def test_that_the_period_of_a_grid_of_crowns_is_found(spacing, crown_share):
    found = period.PeriodEstimator().estimate(_grid_frame(spacing, crown_share), 40, 300)
    assert found is not None and abs(found - spacing) <= PERIOD_TOLERANCE * spacing, found


def test_that_a_frame_without_a_repeat_has_no_period():
    rng = np.random.RandomState(3)
    flat = np.full((288, 352), 90, np.uint8)
    assert period.PeriodEstimator().estimate(flat, 40, 300) is None
    noise = rng.randint(0, 255, (288, 352)).astype(np.uint8)  # no structure at crown scale
    assert period.PeriodEstimator().estimate(noise, 40, 300) is None


def _small_beside_large():
    """A 66 px crown touching a 102 px one (centres 73 px apart), the bench's 'small' case on synthetic palms:
    seed 0 of host_tools.detection.period_pairs."""
    return period_pairs.pair_frame(0)


def _found(detections, crowns):
    return period_pairs.found(detections, crowns)


def test_that_the_period_stage_keeps_a_small_crown_touching_a_larger_one_apart():
    image, crowns, distance = _small_beside_large()
    model = foranav_model.load_model(str(SHIPPED_MODEL))
    today = detector_core.TreeDetector(model).detect(image)
    staged = detector_core.TreeDetector(model, detector_core.DetectorSettings(
        grouping="period", period_px=distance)).detect(image)
    # today's grouping: one detection, on the large crown (the small one's peaks fall in its group)
    assert len(today) == 1 and _found(today, crowns) == [False, True]
    # the period stage (the period given, as the flight map would): both crowns, each once
    assert len(staged) == 2 and _found(staged, crowns) == [True, True]


def test_that_the_default_is_todays_grouping_and_period_without_a_clear_period_falls_back_to_it():
    image, _crowns, _distance = _small_beside_large()
    model = foranav_model.load_model(str(SHIPPED_MODEL))
    assert detector_core.DetectorSettings().grouping == "nms"
    today = detector_core.TreeDetector(model).detect(image)
    staged = detector_core.TreeDetector(model, detector_core.DetectorSettings(grouping="period"))
    value = features.bgr_to_hsv(image)[:, :, 2].copy()
    assert staged.suppression_radius(value) is None  # two unequal crowns: no clear repeat in this frame
    assert staged.detect(image) == today


def test_that_a_grid_frame_gets_a_suppression_radius_tied_to_its_period_not_its_crowns():
    model = foranav_model.load_model(str(SHIPPED_MODEL))
    detector = detector_core.TreeDetector(model, detector_core.DetectorSettings(grouping="period"))
    for crown_share in (0.7, 1.0):  # same spacing, different crowns: the same radius
        radius = detector.suppression_radius(_grid_frame(100, crown_share))
        assert abs(radius - detector_core.PERIOD_SUPPRESSION * 100) <= PERIOD_TOLERANCE * 100


@pytest.mark.parametrize("grouping,period_px", [("blobs", None), ("period", 0.0), ("period", float("nan"))])
def test_that_bad_period_settings_are_refused(grouping, period_px):
    with pytest.raises(ValueError):
        detector_core.DetectorSettings(grouping=grouping, period_px=period_px)


@pytest.mark.parametrize("name,value", [("grouping", "blobs"), ("periodpx", "0"), ("periodpx", "-80"),
                                        ("periodpx", "inf")])
def test_that_the_camera_refuses_bad_period_parameters(name, value):
    with pytest.raises(ValueError, match=name):
        ModuleRunner(params={name: value})


def test_that_the_camera_parameters_select_the_period_stage():
    runner = ModuleRunner(params={"grouping": "period", "periodpx": "88"})
    settings = runner.instance.currentDetector().settings
    assert (settings.grouping, settings.period_px) == ("period", 88.0)
    default = ModuleRunner().instance.currentDetector().settings
    assert (default.grouping, default.period_px) == ("nms", None)
