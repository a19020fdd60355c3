"""The optional second stage (issue 9): a finer-HOG linear SVM that models trained on survey imagery add."""
import io

import cv2
import numpy as np
import pytest

import host_tools.detection  # noqa: F401
from host_tools.annotations import Box
from host_tools.detection import common, dataset, evaluation, synthetic, training

import foranav_detector as detector_core
import foranav_features as features
import foranav_model


def with_second_stage(model, bias, threshold):
    """The model with a constant second stage: every window scores `bias`."""
    model.second_window = 48
    model.second_weights = np.zeros(features.hog_descriptor_length(48), np.float32)
    model.second_bias = bias
    for domain in model.domains:
        domain.second_threshold = threshold
    return model


def test_that_the_second_stage_hog_at_the_top_layer_size_is_the_top_layer_hog():
    value = cv2.extractChannel(features.bgr_to_hsv(synthetic.scene(5)[0]), 2)[40:160, 60:180]
    small = cv2.resize(value, (24, 24), interpolation=cv2.INTER_AREA)
    reference = features.top_layer_hog(cv2.copyMakeBorder(small, 1, 1, 1, 1, cv2.BORDER_REPLICATE))
    assert np.allclose(features.second_stage_hog(value, 24), reference, atol=1e-5)
    assert features.second_stage_hog(value, 48).shape == (features.hog_descriptor_length(48),) == (2916,)


def test_that_a_model_without_a_second_stage_keeps_its_bytes_and_one_with_it_round_trips():
    path = common.model_path("oil_palm")
    shipped = foranav_model.load_model(path)
    buffer = io.BytesIO()
    foranav_model.save_model(shipped, buffer)
    with open(path, "rb") as handle:
        assert buffer.getvalue() == handle.read()
    model = with_second_stage(shipped, 0.25, -0.5)
    model.second_weights[:3] = (1.0, -2.0, 3.0)
    buffer = io.BytesIO()
    foranav_model.save_model(model, buffer)
    buffer.seek(0)
    loaded = foranav_model.load_model(buffer)
    assert loaded.second_window == 48 and loaded.second_bias == pytest.approx(0.25)
    assert np.array_equal(loaded.second_weights, model.second_weights)
    assert loaded.domains[0].second_threshold == pytest.approx(-0.5)


def test_that_a_model_with_part_of_a_second_stage_is_refused_in_one_line():
    model = with_second_stage(common.load("oil_palm"), 0.0, 0.0)
    arrays = model.to_arrays()
    del arrays["second_bias"]
    with pytest.raises(foranav_model.ModelFormatError) as error:
        foranav_model.model_from_arrays(arrays, "m.npz")
    assert "second stage incomplete" in str(error.value) and "\n" not in str(error.value)


def test_that_the_second_stage_rejects_the_windows_scoring_at_most_its_threshold():
    frame = synthetic.scene(21)[0]
    plain = detector_core.TreeDetector(common.load("oil_palm")).detect(frame)
    assert plain, "fixture: the shipped model finds the palms"
    passing = detector_core.TreeDetector(with_second_stage(common.load("oil_palm"), 0.0, -0.5)).detect(frame)
    rejecting = detector_core.TreeDetector(with_second_stage(common.load("oil_palm"), 0.0, 0.0)).detect(frame)
    assert passing == plain
    assert rejecting == []


def survey_frames(seeds):
    """Frames of 528x432 px (not flight-camera sized: survey imagery) with palms and a roof."""
    out = []
    for seed in seeds:
        image, palms, roofs = synthetic.scene(seed, width=528, height=432, palms=6, roofs=1, diameter=(60, 90))
        boxes = [Box("%d.png" % seed, cx, cy, d, d, "oil_palm") for cx, cy, d in palms]
        boxes += [Box("%d.png" % seed, cx, cy, d, d * 0.7, "roof") for cx, cy, d in roofs]
        out.append(dataset.Frame("%d.png" % seed, image, boxes))
    return out


def test_that_training_on_survey_imagery_adds_a_second_stage_that_detection_and_crops_use():
    train_frames, test_frames = survey_frames(range(700, 710)), survey_frames(range(800, 804))
    model = training.train([training.Imagery("survey", train_frames)], "oil_palm", seed=2)
    assert model.second_window == training.SECOND_STAGE_WINDOW
    result = evaluation.evaluate_frames(model, test_frames, detector_core.DetectorSettings(max_detections=None),
                                        crown_px="boxes", funnel=True)
    assert result["recall"] >= 0.6 and result["precision"] >= 0.8, result
    assert result["funnel"]["colour"] >= result["funnel"]["second"] >= result["funnel"]["texture"]
    camera = training.train([training.Imagery("camera", [dataset.Frame("c.png", synthetic.scene(s)[0], [
        Box("c.png", cx, cy, d, d, "oil_palm") for cx, cy, d in synthetic.scene(s)[1]]) for s in range(900, 906)])],
        "oil_palm", seed=2)
    assert camera.second_window is None  # flight-camera (rendered) models stay one stage
