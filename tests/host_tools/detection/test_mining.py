"""Hard-negative mining of survey imagery (issue 9): in proportion to its crowns, not ten per image."""
import numpy as np

import host_tools.detection  # noqa: F401
from host_tools.annotations import Box
from host_tools.detection import common, dataset, examples, synthetic

import foranav_features as features


def survey_frame(seed, palms):
    """A 704x576 frame (not flight-camera sized: survey imagery) with palms and a roof, all labelled."""
    image, placed, roofs = synthetic.scene(seed, width=704, height=576, palms=palms, roofs=1, diameter=(60, 80))
    boxes = [Box("s.png", cx, cy, d, d, "oil_palm") for cx, cy, d in placed]
    boxes += [Box("s.png", cx, cy, d, d * 0.7, "roof") for cx, cy, d in roofs]
    return dataset.Frame("s.png", image, boxes)


def test_that_survey_frames_are_mined_in_proportion_to_their_crowns():
    few, many = survey_frame(1, palms=2), survey_frame(2, palms=30)
    assert len(many.trees("oil_palm")) > examples.HARD_NEGATIVES_PER_FRAME
    assert examples.hard_negative_quota(few, "oil_palm") == examples.HARD_NEGATIVES_PER_FRAME
    assert examples.hard_negative_quota(many, "oil_palm") == len(many.trees("oil_palm"))


def test_that_a_survey_frame_full_of_false_alarms_gives_its_whole_quota_and_a_camera_frame_ten():
    model = common.load("oil_palm")
    model.svm_bias += 3.0  # a model early in its training: it fires all over the frame
    frame = survey_frame(3, palms=30)
    quota = examples.hard_negative_quota(frame, "oil_palm")
    survey = examples.hard_negatives([frame], "oil_palm", model, np.random.RandomState(0), survey=True)
    camera = examples.hard_negatives([frame], "oil_palm", model, np.random.RandomState(0), survey=False)
    assert survey.shape == (quota, features.hog_descriptor_length())
    assert len(camera) == examples.HARD_NEGATIVES_PER_FRAME < quota
