"""Training pieces: the linear SVM solver and the threshold calibration."""
import numpy as np
import pytest

import host_tools.detection  # noqa: F401
from host_tools.detection import evaluation, svm, synthetic, training
import foranav_detector as detector_core


def test_that_the_svm_separates_linearly_separable_data_with_a_margin():
    rng = np.random.RandomState(0)
    x = np.vstack([rng.normal(2.0, 0.5, (50, 5)), rng.normal(-2.0, 0.5, (80, 5))])
    y = np.concatenate([np.ones(50), -np.ones(80)])
    weights, bias = svm.train_linear_svm(x, y, c=10.0, seed=1)
    margins = y * (x.dot(weights) + bias)
    assert (margins > 0).all()
    assert np.percentile(margins, 5) > 0.5


def test_that_the_svm_learns_an_offset_through_its_bias():
    rng = np.random.RandomState(1)
    x = rng.uniform(0, 1, (200, 1))
    y = np.where(x[:, 0] > 0.7, 1, -1)
    weights, bias = svm.train_linear_svm(x, y, c=100.0, seed=2)
    boundary = -bias / weights[0]
    assert boundary == pytest.approx(0.7, abs=0.05)


def test_that_the_svm_is_deterministic_for_a_seed_and_refuses_one_class():
    rng = np.random.RandomState(2)
    x = rng.normal(0, 1, (60, 3))
    y = np.where(x[:, 0] + 0.3 * rng.normal(size=60) > 0, 1, -1)
    first = svm.train_linear_svm(x, y, seed=3)
    second = svm.train_linear_svm(x, y, seed=3)
    assert np.array_equal(first[0], second[0]) and first[1] == second[1]
    with pytest.raises(ValueError):
        svm.train_linear_svm(x, np.ones(60), seed=3)


def test_that_a_threshold_below_a_quantile_lies_between_samples():
    values = np.array([0.1, 0.2, 0.3, 0.4])
    assert training._below_quantile(values, 0.0) < 0.1
    assert 0.1 < training._below_quantile(values, 0.25) < 0.2


def test_that_training_needs_trees_of_the_species():
    frames = synthetic.annotated_frames(range(10))
    with pytest.raises(ValueError, match="no complete 'citrus'"):
        training.train(frames, "citrus", seed=0)


def test_that_the_edge_test_is_calibrated_to_the_best_frame_f1_of_its_candidates():
    model = synthetic.small_model(seed=1, frames=40)
    frames = synthetic.annotated_frames(range(100, 112))
    messages = []
    training._calibrate_edge(model, [("default", frames)], messages.append)
    candidates = (model.svm_threshold,) + training.EDGE_THRESHOLDS
    assert model.edge_threshold in candidates and "edge test on 12 frames" in messages[0]

    def f1(edge):
        return evaluation.evaluate_frames(model, frames, detector_core.DetectorSettings(edge_threshold=edge))["f1"]
    chosen = f1(model.edge_threshold)
    assert all(chosen >= f1(edge) - 1e-6 for edge in candidates)
