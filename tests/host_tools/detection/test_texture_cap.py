"""The texture threshold of survey imagery is capped by its least textured training image
(calibration.texture_cap): the cue follows each image's sharpness, so a threshold chosen on a sharp held-back
image must not reject the crowns of a blurrier one."""
import cv2
import numpy as np
import pytest

import host_tools.detection  # noqa: F401
from host_tools.detection import calibration, dataset, evaluation, training

import foranav_detector as detector_core
import foranav_features as features

from tests.host_tools.detection.test_second_stage import survey_frames


def blurred(frames, sigma=1.6):
    """The frames as a softer camera or a higher zoom would give them (same boxes)."""
    return [dataset.Frame(f.path, cv2.GaussianBlur(f.bgr, (0, 0), sigma), f.boxes) for f in frames]


def crown_textures(frame, margin):
    return [features.hog_texture(frame.value[dataset.pixel_window(frame, b.x_center, b.y_center,
                                                                  dataset.crown_size(b) * margin)])
            for b in frame.trees("oil_palm")
            if frame.window_fits(b.x_center, b.y_center, dataset.crown_size(b) * margin)]


def test_that_the_cap_is_the_margin_times_the_least_textured_frames_low_quantile():
    frames = survey_frames(range(700, 703)) + blurred(survey_frames(range(703, 705)))
    margin = training.DEFAULT_MARGIN
    per_frame = [np.percentile(crown_textures(f, margin), 100 * calibration.TEXTURE_CAP_QUANTILE) for f in frames]
    cap = calibration.texture_cap(frames, "oil_palm", margin)
    assert cap == pytest.approx(calibration.TEXTURE_CAP_MARGIN * min(per_frame), rel=1e-6)
    assert min(per_frame) < 0.7 * max(per_frame)  # the blurred frames are the least textured
    assert calibration.texture_cap([dataset.Frame("empty.png", frames[0].bgr, [])], "oil_palm", 1.3) is None


def test_that_calibration_keeps_the_variance_threshold_under_the_cap():
    frames = survey_frames(range(700, 706))
    model = training.train([training.Imagery("survey", frames)], "oil_palm", seed=2)
    calibration.calibrate(model, 0, frames[:2], np.random.RandomState(0), lambda message: None, texture_cap=1e-7)
    assert model.domains[0].variance_threshold <= 1e-7


def texture_losses(model, frames):
    """Crowns that pass the second stage but fail the texture test, and how many passed the second stage."""
    result = evaluation.evaluate_frames(model, frames, detector_core.DetectorSettings(max_detections=None),
                                        crown_px="boxes", funnel=True)
    return result["funnel"]["second"] - result["funnel"]["texture"], result["funnel"]["second"]


def test_that_a_model_trained_on_sharp_and_soft_images_keeps_the_soft_crowns(monkeypatch):
    frames = survey_frames(range(700, 706)) + blurred(survey_frames(range(706, 710)))
    unseen = blurred(survey_frames(range(800, 804)), sigma=2.0)  # softer than every training image
    model = training.train([training.Imagery("survey", frames)], "oil_palm", seed=2)
    lost, passed = texture_losses(model, unseen)
    assert passed >= 12 and lost <= 0.1 * passed, (lost, passed)
    monkeypatch.setattr(calibration, "TEXTURE_CAP_MARGIN", 1e6)  # no cap: the held-back images' pick
    uncapped = training.train([training.Imagery("survey", frames)], "oil_palm", seed=2)
    lost, passed = texture_losses(uncapped, unseen)
    assert lost >= 0.5 * passed, (lost, passed)  # the failure the cap is there for
