"""The second stage's radial cue (foranav_features.radial_descriptor): gradients against the lines from the
window's centre, the shape of fronds radiating from a crown's centre."""
import io

import cv2
import numpy as np
import pytest

import host_tools.detection  # noqa: F401
from host_tools.detection import common, evaluation, training

import foranav_detector as detector_core
import foranav_features as features
import foranav_model

from tests.host_tools.detection.test_second_stage import survey_frames, with_second_stage


def star(side, offset=0.0, spokes=8):
    """A grey star of `spokes` bright rays about a point `offset` x side right of the window's centre."""
    ys, xs = np.mgrid[0:side, 0:side] - (side - 1) / 2.0
    return (128 + 100 * np.cos(spokes * np.arctan2(ys, xs - offset * side))).astype(np.uint8)


def tangential_share(descriptor):
    """Share of the inner rings' gradient at 75-90 deg to the radial line (edges along the rays)."""
    shape = descriptor[:features.RADIAL_RINGS * features.RADIAL_BINS].reshape(features.RADIAL_RINGS, -1)
    return float(shape[:4, -1].mean()) / features.RADIAL_GAIN


def test_that_a_centred_star_has_its_gradients_across_the_radial_lines_and_a_shifted_one_does_not():
    centred = features.radial_descriptor(star(48))
    shifted = features.radial_descriptor(star(48, offset=0.3))
    assert centred.shape == (features.RADIAL_LENGTH,)
    assert tangential_share(centred) > 0.8 > 0.3 > tangential_share(shifted)


def test_that_the_radial_cue_is_the_same_for_a_rotated_or_mirrored_window():
    rng = np.random.RandomState(3)
    window = cv2.GaussianBlur(rng.randint(0, 255, (48, 48)).astype(np.uint8), (5, 5), 1.5)
    reference = features.radial_descriptor(window)
    for turned in (np.rot90(window), np.rot90(window, 2), window[:, ::-1], window[::-1]):
        assert np.allclose(features.radial_descriptor(np.ascontiguousarray(turned)), reference, atol=1e-5)


def test_that_the_descriptor_of_each_kind_has_its_length_and_an_unknown_kind_is_refused():
    value = star(120)
    for kind in features.SECOND_STAGE_KINDS:
        assert features.second_stage_descriptor(value, 48, kind).shape == (features.second_stage_length(48, kind),)
    assert features.second_stage_length(48, "hog+radial") == 2916 + features.RADIAL_LENGTH
    with pytest.raises(ValueError, match="not one of"):
        features.second_stage_descriptor(value, 48, "sift")


def radial_model():
    model = with_second_stage(common.load("oil_palm"), 0.25, -0.5)
    model.second_kind = "hog+radial"
    model.second_weights = np.zeros(features.second_stage_length(48, "hog+radial"), np.float32)
    model.second_weights[-features.RADIAL_LENGTH] = 2.0
    return model


def test_that_a_radial_second_stage_round_trips_and_a_hog_one_writes_no_kind():
    model = radial_model()
    buffer = io.BytesIO()
    foranav_model.save_model(model, buffer)
    buffer.seek(0)
    loaded = foranav_model.load_model(buffer)
    assert loaded.second_kind == "hog+radial"
    assert np.array_equal(loaded.second_weights, model.second_weights)
    assert loaded.second_score(star(120)) == pytest.approx(model.second_score(star(120)))
    assert "second_kind" not in with_second_stage(common.load("oil_palm"), 0.0, 0.0).to_arrays()


@pytest.mark.parametrize("change, message", [
    (lambda arrays: arrays.update(second_kind=np.array("sift")), "second_kind 'sift' is not one of"),
    (lambda arrays: arrays.update(second_kind=np.array(1)), "field second_kind has the wrong type"),
    (lambda arrays: arrays.pop("second_kind"), "second_weights has 2956 values, its descriptor has 2916"),
])
def test_that_a_damaged_second_kind_is_refused_in_one_line(change, message):
    error = refusal_of_damaged(change)
    assert message in error and "\n" not in error


def refusal_of_damaged(change):
    """The loader's message for radial_model()'s arrays after change(arrays)."""
    arrays = radial_model().to_arrays()
    change(arrays)
    with pytest.raises(foranav_model.ModelFormatError) as error:
        foranav_model.model_from_arrays(arrays, "m.npz")
    return str(error.value)


def test_that_training_with_the_radial_cue_stores_it_and_detects_the_palms():
    train_frames, test_frames = survey_frames(range(700, 710)), survey_frames(range(800, 804))
    model = training.train([training.Imagery("survey", train_frames)], "oil_palm", seed=2, second_kind="hog+radial")
    assert model.second_kind == "hog+radial"
    assert model.second_weights.shape == (features.second_stage_length(48, "hog+radial"),)
    assert np.any(model.second_weights[-features.RADIAL_LENGTH:] != 0)
    result = evaluation.evaluate_frames(model, test_frames, detector_core.DetectorSettings(max_detections=None),
                                        crown_px="boxes", funnel=True)
    assert result["recall"] >= 0.6 and result["precision"] >= 0.8, result
