"""The second stage scored over the window's four quarter turns (model field second_views): a crown seen
from straight above has no "up", so the mean HOG of the turns scores every turn of a window alike."""
import io

import cv2
import numpy as np
import pytest

import host_tools.detection  # noqa: F401
from host_tools.detection import common, training

import foranav_features as features
import foranav_model

from tests.host_tools.detection.test_radial_cue import radial_model, refusal_of_damaged, star
from tests.host_tools.detection.test_second_stage import survey_frames


def textured_window(seed, side=48):
    """A blurred random window whose HOG changes when it turns (no symmetry to hide a mistake)."""
    rng = np.random.RandomState(seed)
    return cv2.GaussianBlur(rng.randint(0, 255, (side, side)).astype(np.uint8), (5, 5), 1.2)


@pytest.mark.parametrize("kind", features.SECOND_STAGE_KINDS)
def test_that_four_views_give_every_quarter_turn_of_a_window_the_same_descriptor(kind):
    window = textured_window(4)
    reference = features.second_stage_descriptor(window, 48, kind, views=4)
    assert reference.shape == (features.second_stage_length(48, kind),)
    for turns in (1, 2, 3):
        turned = np.ascontiguousarray(np.rot90(window, turns))
        assert np.allclose(features.second_stage_descriptor(turned, 48, kind, views=4), reference, atol=1e-5)
        assert not np.allclose(features.second_stage_descriptor(turned, 48, kind), features.second_stage_descriptor(
            window, 48, kind), atol=1e-3)  # one view does see the turn


def test_that_one_view_is_the_descriptor_as_before_and_four_are_the_mean_of_the_turns():
    window = textured_window(5)
    hog = features.second_stage_hog(window, 48)
    assert np.array_equal(features.second_stage_descriptor(window, 48, "hog"), hog)
    turns = [features.second_stage_hog(np.ascontiguousarray(np.rot90(window, t)), 48) for t in range(4)]
    assert np.allclose(features.second_stage_descriptor(window, 48, "hog", views=4), np.mean(turns, axis=0),
                       atol=1e-6)
    with pytest.raises(ValueError, match="views 8 is not one of"):
        features.second_stage_descriptor(window, 48, "hog", views=8)


def test_that_four_views_round_trip_and_one_view_writes_no_field():
    model = radial_model()
    assert "second_views" not in model.to_arrays()  # files written before the field keep their bytes
    model.second_views = 4
    buffer = io.BytesIO()
    foranav_model.save_model(model, buffer)
    buffer.seek(0)
    loaded = foranav_model.load_model(buffer)
    assert loaded.second_views == 4
    window = star(120, offset=0.1)
    assert loaded.second_score(window) == pytest.approx(model.second_score(window))
    assert loaded.second_score(window) == pytest.approx(
        loaded.second_score(np.ascontiguousarray(np.rot90(window))), abs=1e-4)


@pytest.mark.parametrize("change, message", [
    (lambda arrays: arrays.update(second_views=np.array(8)), "second_views 8 is not one of"),
    (lambda arrays: arrays.update(second_views=np.array("4")), "field second_views has the wrong type"),
    (lambda arrays: arrays.update(second_views=np.array([4, 4])), "field second_views has the wrong type"),
])
def test_that_a_damaged_second_views_is_refused_in_one_line(change, message):
    error = refusal_of_damaged(change)
    assert message in error and "\n" not in error


def test_that_training_stores_the_views_it_was_asked_for():
    frames = survey_frames(range(700, 706))
    four = training.train([training.Imagery("survey", frames)], "oil_palm", seed=2, second_views=4)
    one = training.train([training.Imagery("survey", frames)], "oil_palm", seed=2, second_views=1)
    assert (four.second_views, one.second_views) == (4, 1)
    assert training.DEFAULT_SECOND_VIEWS in features.SECOND_STAGE_VIEWS
    # the SVM learns from the same single windows; only the scoring (and so the calibration) differs
    assert np.array_equal(four.second_weights, one.second_weights)


def test_that_a_flight_model_has_no_second_stage_to_view():
    model = common.load("oil_palm")
    assert model.second_window is None and model.second_views == 1
