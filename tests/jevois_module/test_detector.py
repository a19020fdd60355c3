"""The detector core (foranav_detector): fast per-frame path vs the per-window reference, detections."""
import math

import numpy as np
import pytest

import host_tools.detection  # noqa: F401
import foranav_detector as detector_core
import foranav_grouping as grouping
import foranav_features as features
from host_tools.detection import reference, synthetic

# The fast path averages each 2 x 2 pixel group of 16-bit votes (rounded) where the reference adds them
# exactly: scores agree to a few thousandths (scores of trees are ~1).
SCORE_TOLERANCE = 0.01
CENTRE_TOLERANCE_PX = 0.5  # same candidates -> same fused centres, up to the score differences above
FOUND_WITHIN_PX = 16  # a detection counts as the palm when its centre is this close (crowns: 65-130 px)
MIN_FOUND = 0.6  # of the palms, for a model trained in a second on 40 synthetic frames
MAX_MEAN_CENTRE_ERROR_PX = 10.0


@pytest.fixture(scope="module")
def model():
    return synthetic.small_model(seed=1, frames=40)


@pytest.fixture(scope="module")
def scenes():
    return [synthetic.scene(seed) for seed in range(2000, 2008)]


@pytest.mark.parametrize("step", [1, 2, 3, 8])
def test_that_the_fast_score_maps_equal_the_per_window_reference(model, scenes, step):
    detector = detector_core.TreeDetector(model, detector_core.DetectorSettings(step=step))
    image = scenes[0][0]
    value = np.ascontiguousarray(features.bgr_to_hsv(image)[:, :, 2])
    fast = detector.score_maps(value)
    slow = reference.reference_score_maps(detector, value)
    assert [p.window for p, _ in fast] == [p.window for p, _ in slow]
    for (_, a), (_, b) in zip(fast, slow):
        assert a.shape == b.shape
        assert np.abs(a - b).max() <= SCORE_TOLERANCE


def test_that_the_fast_and_reference_detectors_report_the_same_trees(model, scenes):
    detector = detector_core.TreeDetector(model)
    for image, _palms, _roofs in scenes[:3]:
        fast = detector.detect(image)
        slow = reference.reference_detect(detector, image)
        assert len(fast) == len(slow)
        for a, b in zip(fast, slow):
            assert math.hypot(a.x - b.x, a.y - b.y) <= CENTRE_TOLERANCE_PX
            assert a.score == pytest.approx(b.score, abs=SCORE_TOLERANCE)


def test_that_palms_are_found_near_their_centres(model, scenes):
    detector = detector_core.TreeDetector(model)
    found = total = 0
    errors = []
    for image, palms, _roofs in scenes:
        detections = detector.detect(image)
        for cx, cy, _d in palms:
            total += 1
            distances = [math.hypot(d.x - cx, d.y - cy) for d in detections]
            if distances and min(distances) <= FOUND_WITHIN_PX:
                found += 1
                errors.append(min(distances))
    assert found >= MIN_FOUND * total
    assert np.mean(errors) < MAX_MEAN_CENTRE_ERROR_PX


def test_that_detections_are_sorted_best_first_and_inside_the_frame(model, scenes):
    detector = detector_core.TreeDetector(model)
    for image, _palms, _roofs in scenes:
        detections = detector.detect(image)
        assert [d.score for d in detections] == sorted((d.score for d in detections), reverse=True)
        for d in detections:
            assert 0 <= d.x - d.w / 2 and d.x + d.w / 2 <= image.shape[1]
            assert 0 <= d.y - d.h / 2 and d.y + d.h / 2 <= image.shape[0]


def test_that_an_empty_field_gives_no_detections(model):
    image = synthetic.ground(np.random.RandomState(5), 288, 352)
    assert detector_core.TreeDetector(model).detect(image) == []


def test_that_a_palm_cut_by_the_frame_edge_is_not_reported(model):
    rng = np.random.RandomState(6)
    image = synthetic.ground(rng, 288, 352)
    synthetic.draw_palm(image, rng, 10, 144, 100)  # centre 10 px from the left edge: 40 % of it outside
    detections = detector_core.TreeDetector(model).detect(image)
    assert not [d for d in detections if d.x < 60]


def test_that_detection_is_deterministic(model, scenes):
    image = scenes[1][0]
    first = detector_core.TreeDetector(model).detect(image)
    second = detector_core.TreeDetector(model).detect(image.copy())
    assert first == second


def test_that_stricter_thresholds_only_remove_detections(model, scenes):
    image = scenes[2][0]
    loose = detector_core.TreeDetector(model).detect(image)
    strict = detector_core.TreeDetector(model, detector_core.DetectorSettings(svm_threshold=10.0)).detect(image)
    assert strict == [] and len(loose) > 0
    few = detector_core.TreeDetector(model, detector_core.DetectorSettings(max_detections=1)).detect(image)
    assert few == loose[:1]


def test_that_window_sizes_scale_with_the_frame_width_in_multiples_of_24(model):
    assert detector_core.model_window_sizes(model, 352) == tuple(model.window_sizes)
    sizes = detector_core.model_window_sizes(model, 704)
    assert all(s % features.HOG_WINDOW == 0 for s in sizes)
    assert sizes == tuple(2 * w for w in model.window_sizes)


def test_that_windows_larger_than_the_frame_and_bad_settings_are_refused(model):
    detector = detector_core.TreeDetector(model, detector_core.DetectorSettings(window_sizes=(400,)))
    with pytest.raises(ValueError, match="do not fit"):
        detector.detect(np.zeros((288, 352, 3), np.uint8))
    with pytest.raises(ValueError):
        detector_core.DetectorSettings(step=0)
    with pytest.raises(ValueError):
        detector_core.DetectorSettings(nms_overlap=1.5)


def test_that_the_paper_step_and_odd_window_sizes_still_detect(model, scenes):
    image, palms, _ = scenes[0]
    settings = detector_core.DetectorSettings(step=detector_core.PAPER_STEP, window_sizes=(100, 130))
    detections = detector_core.TreeDetector(model, settings).detect(image)
    assert all(0 <= d.x <= 352 and 0 <= d.y <= 288 for d in detections)


def _representative(model, group, accepted, hs_threshold):
    detector = detector_core.TreeDetector(model, detector_core.DetectorSettings(hs_threshold=hs_threshold))
    hsv = np.full((288, 352, 3), 100, np.uint8)  # the colour test's outcome comes from hs_threshold alone
    return detector.representative_first(group, accepted, hsv, hs_threshold, None)


def test_that_an_anchor_dropped_as_a_neighbours_crown_leaves_the_crown_sized_window_it_holds(model):
    # sweep flight 6 at 1.35 m: tree 4 accepted from a 110 px window; the 168 px anchor of tree 3's group
    # reaches 32 px towards tree 4 and shares more than half of that window; the 96 px window it holds is on
    # tree 3 (95 px crown)
    accepted = [grouping.Detection(157.0, 59.0, 85.0, 85.0, 0.3)]
    anchor = (-0.90, 170.0, 142.0, 168.0)
    crown_sized = (-1.09, 182.0, 174.0, 96.0)
    larger = (-1.15, 177.0, 171.0, 120.0)
    elsewhere = (-1.20, 120.0, 142.0, 96.0)  # in the group, not held by the anchor
    chosen = _representative(model, [anchor, crown_sized, larger, elsewhere], accepted, -2.0)
    assert chosen[0] is crown_sized
    assert sorted(map(id, chosen)) == sorted(map(id, [anchor, crown_sized, larger, elsewhere]))
    # the anchor is kept when it is not part of an accepted crown; nothing when no window passes colour
    assert _representative(model, [anchor, crown_sized], [], -2.0)[0] is anchor
    assert _representative(model, [anchor, crown_sized], [], 2.0) is None
    # a held window inside the accepted crown too is not taken
    held_duplicate = (-1.1, 160.0, 66.0, 96.0)
    assert grouping.inside_a_crown(held_duplicate, accepted, model.window_margin)
    assert _representative(model, [(-0.9, 160.0, 70.0, 168.0), held_duplicate], accepted, -2.0) is None
