"""The straightforward per-window implementation of the detector pipeline, for checking and benchmarking.

Same windows, features, model and post-processing as the camera's fast path (foranav_detector), but every
window is cut out, downscaled and described on its own, the way the paper's pipeline reads: crop -> HSV ->
value -> downscale to W_d -> HOG -> SVM. The fast path must agree with it (tests) and beat it (bench).
"""
from typing import Any

import numpy as np

import host_tools.detection  # noqa: F401  (puts the camera module folder on sys.path)

import foranav_features as features


def score_map_shape(plan: Any) -> tuple[int, int]:
    """(rows, cols) of a size's score map: window origins on the lattice, every `stride`-th one."""
    return (-(-plan.map_height // plan.stride), -(-plan.map_width // plan.stride))


def reference_score_maps(detector: Any, value: np.ndarray) -> list[np.ndarray]:
    """[(plan, scores)] like TreeDetector.score_maps, one window at a time."""
    out = []
    for plan in detector.plans(*value.shape):
        if not plan.usable:
            continue
        rows, cols = score_map_shape(plan)
        frame = value[:plan.crop_height, :plan.crop_width]  # the fast path's whole-block crop
        scores = np.empty((rows, cols), np.float32)
        for row in range(rows):
            for col in range(cols):
                x0, y0 = plan.window_origin(row, col)
                small = features.window_with_context(frame, x0, y0, plan.window)
                scores[row, col] = detector.model.score(features.top_layer_hog(small))
        out.append((plan, scores))
    return out


def reference_detect(detector: Any, bgr: np.ndarray) -> list:
    """Detections of the per-window pipeline (same post-processing as the fast path)."""
    hsv = features.bgr_to_hsv(bgr)
    value = np.ascontiguousarray(hsv[:, :, 2])
    return detector.detections_from_maps(reference_score_maps(detector, value), hsv, value)
