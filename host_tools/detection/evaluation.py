"""Evaluating a model: the paper's crop protocol and frame-level detection (pure: data + model in, figures out).

Crop protocol (paper section IV-A): n positive crops, each one complete tree of the species, and n negative
crops that do not contain a complete tree of it; a crop is classified positive when the window passes all
three tests (top-layer SVM, hue/saturation similarity, bottom-layer HOG variance). Crops come either from a
crops CSV (``image,class,category`` as written by ``foranav synth``: each image is one window) or are cut
from annotated frames with a seed (positives: complete trees, window = crown x the model's margin;
negatives: other labels, windows shifted off a tree, background).

Frame level: the detector on whole frames; a detection is a hit when its centre lies inside a not yet
matched complete ground-truth box of the species (detections best first); precision, recall, F1, and the
centre error of the hits in pixels (what the flight app servos on).
"""
import csv
import io
import math
from pathlib import Path

import cv2
import numpy as np

from host_tools.detection import dataset
from host_tools.errors import ForaNavError

import foranav_detector as detector_core
import foranav_features as features

CROPS_HEADER = ("image", "class", "category")


def classify_window(model, value, hsv, settings=None, small=None):
    """(is_tree, svm score, hs similarity, variance) of one window given as full-resolution value and HSV
    (and optionally its top-layer input with context, see foranav_features.window_with_context)."""
    settings = settings or detector_core.DetectorSettings()

    def threshold(name):
        value = getattr(settings, name)
        return float(getattr(model, name) if value is None else value)

    small = _downscale_crop(value) if small is None else small
    score = model.score(features.top_layer_hog(small))
    similarity = features.hs_similarity(hsv, model.template_hue, model.template_sat)
    variance = features.hog_texture(value)
    is_tree = (score > threshold("svm_threshold") and similarity > threshold("hs_threshold")
               and variance > threshold("variance_threshold"))
    return is_tree, score, similarity, variance


def _downscale_crop(value):
    """A crop is the whole window: downscale it to W_d x W_d (its border gradients replicate)."""
    return cv2.resize(value, (features.HOG_WINDOW, features.HOG_WINDOW), interpolation=cv2.INTER_AREA)


def crop_metrics(labels, predictions):
    labels = np.asarray(labels, bool)
    predictions = np.asarray(predictions, bool)
    tp = int((labels & predictions).sum())
    fp = int((~labels & predictions).sum())
    fn = int((labels & ~predictions).sum())
    tn = int((~labels & ~predictions).sum())
    return {
        "accuracy": (tp + tn) / max(1, len(labels)),
        "precision": tp / (tp + fp) if tp + fp else 0.0,
        "recall": tp / (tp + fn) if tp + fn else 0.0,
        "n_pos": int(labels.sum()), "n_neg": int((~labels).sum()),
        "tp": tp, "fp": fp, "fn": fn, "tn": tn,
    }


# ---------------------------------------------------------------------------------------------------------
# Crops


def is_crops_csv(path):
    try:
        with open(path, encoding="utf-8") as handle:
            first = handle.readline()
    except OSError as err:
        raise ForaNavError("%s: cannot read: %s" % (path, err.strerror or err))
    return tuple(h.strip() for h in first.strip().split(",")) == CROPS_HEADER


def read_crops(csv_path):
    """[(image path, is positive, category)] of a crops CSV."""
    csv_path = Path(csv_path)
    rows = list(csv.reader(io.StringIO(csv_path.read_text(encoding="utf-8"))))
    crops = []
    for line_no, row in enumerate(rows[1:], start=2):
        if not row:
            continue
        if len(row) != 3 or row[1] not in ("pos", "neg"):
            raise ForaNavError("%s: line %d: expected image,pos|neg,category" % (csv_path, line_no))
        crops.append((str(csv_path.parent / row[0]), row[1] == "pos", row[2]))
    if not crops:
        raise ForaNavError("%s: no crops" % csv_path)
    return crops


def evaluate_crop_images(model, crops, settings=None):
    labels, predictions = [], []
    for path, positive, _category in crops:
        bgr = dataset.read_image(path)
        hsv = features.bgr_to_hsv(bgr)
        predictions.append(classify_window(model, np.ascontiguousarray(hsv[:, :, 2]), hsv, settings)[0])
        labels.append(positive)
    return crop_metrics(labels, predictions)


def sample_frame_crops(frames, species, margin, n_pos, n_neg, seed, copies=1):
    """[(frame, cx, cy, side, is positive)]: the crop protocol's windows cut from annotated frames.

    copies > 1 adds jittered positives per tree (window 0.88-1.12 x crown x margin, centre moved by up to
    what keeps the crown inside the window), as rendered crop sets do."""
    rng = np.random.RandomState(seed)
    positives, negatives = [], []
    for frame in frames:
        for box in frame.trees(species):
            crown = dataset.crown_size(box)
            for copy in range(copies):
                side = crown * margin * (rng.uniform(0.88, 1.12) if copy else 1.0)
                slack = max(0.0, (side - crown) / 2.0) * 0.8
                cx = box.x_center + (rng.uniform(-slack, slack) if copy else 0.0)
                cy = box.y_center + (rng.uniform(-slack, slack) if copy else 0.0)
                if frame.window_fits(cx, cy, side):
                    positives.append((frame, cx, cy, side, True))
        for box in frame.boxes:
            if box.label and box.label != species:
                side = dataset.crown_size(box) * margin
                if frame.window_fits(box.x_center, box.y_center, side):
                    negatives.append((frame, box.x_center, box.y_center, side, False))
            elif box.label == species:
                side = dataset.crown_size(box) * margin
                angle, shift = rng.uniform(0, 2 * math.pi), rng.uniform(0.4, 0.6) * side
                cx, cy = box.x_center + shift * math.cos(angle), box.y_center + shift * math.sin(angle)
                if frame.window_fits(cx, cy, side):
                    negatives.append((frame, cx, cy, side, False))
        side = rng.uniform(features.HOG_WINDOW * 3, min(frame.width, frame.height))
        cx, cy = rng.uniform(side / 2, frame.width - side / 2), rng.uniform(side / 2, frame.height - side / 2)
        if not dataset.is_tree_window(frame, species, cx, cy, side, margin, 0.3, 1.6):
            negatives.append((frame, cx, cy, side, False))
    return _subsample(positives, n_pos, rng) + _subsample(negatives, n_neg, rng)


def _subsample(items, count, rng):
    if len(items) <= count:
        return items
    return [items[i] for i in sorted(rng.choice(len(items), count, replace=False))]


def evaluate_frame_crops(model, crops, settings=None):
    labels, predictions = [], []
    for frame, cx, cy, side, positive in crops:
        rows, cols = dataset.pixel_window(frame, cx, cy, side)
        small = features.window_with_context(frame.value, cx - side / 2.0, cy - side / 2.0, side)
        predictions.append(classify_window(model, frame.value[rows, cols], frame.hsv[rows, cols], settings,
                                           small)[0])
        labels.append(positive)
    return crop_metrics(labels, predictions)


# ---------------------------------------------------------------------------------------------------------
# Frames


def match_detections(detections, truths):
    """Greedy matching, detections best first -> (hits [(detection, truth)], false positives, misses)."""
    unmatched = list(truths)
    hits, false_positives = [], []
    for detection in detections:
        inside = [t for t in unmatched if abs(detection.x - t.x_center) <= t.width / 2.0
                  and abs(detection.y - t.y_center) <= t.height / 2.0]
        if inside:
            truth = min(inside, key=lambda t: math.hypot(detection.x - t.x_center, detection.y - t.y_center))
            unmatched.remove(truth)
            hits.append((detection, truth))
        else:
            false_positives.append(detection)
    return hits, false_positives, unmatched


def evaluate_frames(model, frames, settings=None):
    detector = detector_core.TreeDetector(model, settings)
    n_hits = n_fp = n_miss = 0
    errors = []
    for frame in frames:
        detections = detector.detect(frame.bgr, frame.hsv)
        hits, false_positives, misses = match_detections(detections, frame.trees(model.species))
        n_hits += len(hits)
        n_fp += len(false_positives)
        n_miss += len(misses)
        errors.extend(math.hypot(d.x - t.x_center, d.y - t.y_center) for d, t in hits)
    precision = n_hits / (n_hits + n_fp) if n_hits + n_fp else 0.0
    recall = n_hits / (n_hits + n_miss) if n_hits + n_miss else 0.0
    return {
        "precision": precision, "recall": recall,
        "f1": 2 * precision * recall / (precision + recall) if precision + recall else 0.0,
        "n_frames": len(frames), "n_trees": n_hits + n_miss, "n_detections": n_hits + n_fp,
        "centre_error_px_mean": float(np.mean(errors)) if errors else None,
        "centre_error_px_median": float(np.median(errors)) if errors else None,
        "centre_error_px_p90": float(np.percentile(errors, 90)) if errors else None,
    }
