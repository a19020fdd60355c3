"""The colour test's definitions (jevois_module/ForaNavTrees/foranav_colour.py)."""
import numpy as np
import pytest

import host_tools.detection  # noqa: F401  (camera module folder on sys.path)
import foranav_colour as colours
import foranav_features as features


def test_that_hs_similarity_is_one_for_the_template_itself_and_lower_for_another_colour():
    rng = np.random.RandomState(3)
    green = np.clip(rng.normal((40, 160, 60), 15, (50, 50, 3)), 0, 255).astype(np.uint8)
    grey = np.clip(rng.normal((140, 140, 145), 15, (50, 50, 3)), 0, 255).astype(np.uint8)
    hue, sat = colours.hs_histograms(colours.colour_region(features.bgr_to_hsv(green)))
    assert hue.shape == sat.shape == (256,)
    assert colours.hs_similarity(features.bgr_to_hsv(green), hue, sat) == pytest.approx(1.0)
    assert colours.hs_similarity(features.bgr_to_hsv(grey), hue, sat) < 0.5


def test_that_the_colour_test_sees_the_crown_in_the_window_centre_not_the_ground_around_it():
    # Fixture: a green crown (central 0.6 of the window) on grey ground, as a 1.3 x crown window frames it.
    rng = np.random.RandomState(5)
    green = (40, 160, 60)
    window = np.clip(rng.normal((140, 140, 145), 15, (100, 100, 3)), 0, 255).astype(np.uint8)
    window[20:80, 20:80] = np.clip(rng.normal(green, 15, (60, 60, 3)), 0, 255).astype(np.uint8)
    crown_only = np.clip(rng.normal(green, 15, (60, 60, 3)), 0, 255).astype(np.uint8)
    hue, sat = colours.hs_histograms(features.bgr_to_hsv(crown_only))
    assert colours.colour_region(window).shape[:2] == (60, 60)
    assert colours.hs_similarity(features.bgr_to_hsv(window), hue, sat) > 0.95
    # the same crown shifted to a corner of the window: the centre now shows ground
    shifted = np.roll(window, (40, 40), axis=(0, 1))
    assert colours.hs_similarity(features.bgr_to_hsv(shifted), hue, sat) < 0.5


def test_that_pearson_of_constant_histograms_is_zero_not_nan():
    assert colours.pearson(np.ones(256), np.arange(256)) == 0.0


def test_that_a_window_that_is_not_hsv_is_refused():
    with pytest.raises(ValueError):
        colours.hs_histograms(np.zeros((10, 10), np.uint8))
