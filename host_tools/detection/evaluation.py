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
import functools
import math
import os
from collections.abc import Sequence
from pathlib import Path

import cv2
import numpy as np

from host_tools import fileio
from host_tools.annotations import Box, read_csv_rows
from host_tools.detection import dataset
from host_tools.errors import ForaNavError

import foranav_detector as detector_core
import foranav_cnn
import foranav_colour as colours
import foranav_features as features
from foranav_model import TreeModel

Cues = tuple[float, float, float]  # (svm score, colour score, texture) of one window
CROPS_HEADER = ("image", "class", "category")


def window_cues(model: TreeModel, domain_index: int, value: np.ndarray, hsv: np.ndarray,
                small: np.ndarray | None = None) -> Cues:
    """(svm score, colour score, texture) of one window given as full-resolution value and HSV (and optionally
    its top-layer input with context, see foranav_features.window_with_context), against one domain."""
    small = _downscale_crop(value) if small is None else small
    score = model.score(features.top_layer_hog(small))
    domain = model.domains[domain_index]
    prepared = colours.prepare_colour_vectors(model.colour_kind, domain.colour_vectors)
    colour = colours.colour_score(model.colour_kind, prepared, domain.colour_bias, *colours.smoothed_hs(hsv))
    return score, colour, features.hog_texture(value)


def frame_window_cues(model: TreeModel, domain_index: int, frame: dataset.Frame, cx: float, cy: float,
                      side: int) -> Cues:
    """window_cues of the window (centre cx, cy; side) of an annotated frame."""
    rows, cols = dataset.pixel_window(frame, cx, cy, side)
    small = features.window_with_context(frame.value, cx - side / 2.0, cy - side / 2.0, side)
    return window_cues(model, domain_index, frame.value[rows, cols], frame.hsv[rows, cols], small)


def passes(model: TreeModel, domain_index: int, cues: Cues, settings: dict | None = None,
           later: tuple[float | None, float | None] = (None, None)) -> bool:
    """Does a window with these cues pass all three tests of the domain (settings override thresholds), and
    the later stages (their scores `later`, see later_scores) the model has?"""
    detector = detector_core.TreeDetector(model, settings)
    detector.domain_index = domain_index
    score, colour, texture = cues
    ok = detector_core.passes_thresholds(score, colour, texture, *detector.thresholds())
    second, logit = later
    if model.second_window is not None:
        ok = ok and second > detector.threshold("second_threshold")
    if model.cnn_onnx is not None:
        ok = ok and logit > detector.threshold("cnn_threshold")
    return ok


@functools.lru_cache(maxsize=4)
def _network(onnx: bytes, side: int) -> foranav_cnn.CnnStage:
    return foranav_cnn.CnnStage(onnx, side)


def later_scores(model: TreeModel, value_window: np.ndarray,
                 hsv_window: np.ndarray) -> tuple[float | None, float | None]:
    """(second-stage score, network logit) of a full-resolution window; None for a stage the model lacks."""
    second = None if model.second_window is None else model.second_score(value_window)
    logit = None if model.cnn_onnx is None else _network(model.cnn_onnx, model.cnn_side).scores([hsv_window])[0]
    return second, logit


def frame_later_scores(model: TreeModel, frame: dataset.Frame, cx: float, cy: float,
                       side: float) -> tuple[float | None, float | None]:
    rows, cols = dataset.pixel_window(frame, cx, cy, side)
    return later_scores(model, frame.value[rows, cols], frame.hsv[rows, cols])


def classify_window(model: TreeModel, value: np.ndarray, hsv: np.ndarray, settings: dict | None = None,
                    small: np.ndarray | None = None, domain_index: int = 0) -> tuple[bool, float, float, float]:
    """(is_tree, svm score, colour score, texture) of one window (see window_cues)."""
    cues = window_cues(model, domain_index, value, hsv, small)
    return (passes(model, domain_index, cues, settings, later_scores(model, value, hsv)),) + tuple(cues)


def nearest_domain(model: TreeModel, hsv: np.ndarray) -> int:
    """The domain index the detector would pick for a frame of this HSV image."""
    return detector_core.TreeDetector(model).select_domain(hsv)


def _downscale_crop(value: np.ndarray) -> np.ndarray:
    """A crop is the whole window: downscale it to W_d x W_d (its border gradients replicate)."""
    return cv2.resize(value, (features.HOG_WINDOW, features.HOG_WINDOW), interpolation=cv2.INTER_AREA)


def crop_metrics(labels: Sequence[bool], predictions: Sequence[bool]) -> dict:
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


def is_crops_csv(path: str | os.PathLike) -> bool:
    first = fileio.read_text(path, "CSV file").partition("\n")[0]
    return tuple(h.strip() for h in first.strip().split(",")) == CROPS_HEADER


def read_crops(csv_path: str | os.PathLike) -> list[tuple[str, bool, str]]:
    """[(image path, is positive, category)] of a crops CSV."""
    csv_path = Path(csv_path)
    rows = read_csv_rows(csv_path, "crops CSV")
    crops, first_line = [], {}
    for line_no, row in enumerate(rows[1:], start=2):
        if not row:
            continue
        if len(row) != 3 or row[1] not in ("pos", "neg"):
            raise ForaNavError("%s: line %d: expected image,pos|neg,category" % (csv_path, line_no))
        if row[0] in first_line:  # one crop counted twice in the accuracy
            raise ForaNavError("%s: line %d: crop %s already listed on line %d (a duplicated row)"
                               % (csv_path, line_no, row[0], first_line[row[0]]))
        first_line[row[0]] = line_no
        crops.append((str(csv_path.parent / row[0]), row[1] == "pos", row[2]))
    if not crops:
        raise ForaNavError("%s: no crops" % csv_path)
    return crops


def evaluate_crop_images(model: TreeModel, crops: Sequence[tuple[str, bool, str]],
                         settings: dict | None = None) -> dict:
    labels, predictions = [], []
    for path, positive, _category in crops:
        bgr = dataset.read_image(path)
        hsv = features.bgr_to_hsv(bgr)
        domain = _domain_index(model, settings, hsv)
        predictions.append(classify_window(model, np.ascontiguousarray(hsv[:, :, 2]), hsv, settings,
                                           domain_index=domain)[0])
        labels.append(positive)
    return crop_metrics(labels, predictions)


def sample_frame_crops(frames: Sequence[dataset.Frame], species: str, margin: float, n_pos: int, n_neg: int,
                       seed: int, copies: int = 1) -> list[tuple]:
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


def _subsample(items: list, count: int, rng: np.random.RandomState) -> list:
    if len(items) <= count:
        return items
    return [items[i] for i in sorted(rng.choice(len(items), count, replace=False))]


def evaluate_frame_crops(model: TreeModel, crops: Sequence[tuple], settings: dict | None = None) -> dict:
    """The crop protocol on windows cut from frames; each frame's domain: the settings', else the nearest."""
    labels, predictions = [], []
    domains = {}
    for frame, cx, cy, side, positive in crops:
        if id(frame) not in domains:
            domains[id(frame)] = _domain_index(model, settings, frame.hsv)
        cues = frame_window_cues(model, domains[id(frame)], frame, cx, cy, side)
        predictions.append(passes(model, domains[id(frame)], cues, settings,
                                  frame_later_scores(model, frame, cx, cy, side)))
        labels.append(positive)
    return crop_metrics(labels, predictions)


def _domain_index(model: TreeModel, settings: dict | None, hsv: np.ndarray) -> int:
    if settings is not None and settings.domain is not None:
        return [d.name for d in model.domains].index(model.domain(settings.domain).name)
    return nearest_domain(model, hsv)


# ---------------------------------------------------------------------------------------------------------
# Frames


def match_detections(detections: Sequence, truths: Sequence[Box]) -> tuple[list[tuple], list, list[Box]]:
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


# "cnn" and "second" count as the stage before them for a model without that stage
FUNNEL_STAGES = ("svm", "peak", "cap", "nms", "colour", "cnn", "second", "texture")


def frame_window_sizes(model: TreeModel, frame: dataset.Frame, crown_px: float | str | None) -> list[int] | None:
    """Window sizes for whole-frame detection: None (the model's, by frame width), from a crown size in
    pixels, or "boxes": from the frame's own typical annotated crown (as a user who knows it would give)."""
    if crown_px is None:
        return None
    if crown_px == "boxes":
        crown_px = frame.typical_crown()
        if crown_px <= 0:
            return None
    sizes = detector_core.crown_window_sizes(model, float(crown_px))
    fitting = tuple(w for w in sizes if w <= min(frame.width, frame.height))
    return fitting or None


def _funnel(trace, truths, settings_threshold):
    """How many of the truths survive each stage: a window centred in the box scoring above the SVM
    threshold; a score-map peak; a peak within the candidate cap; a group's best window after NMS; the
    colour test (passed by the group's window, or by a smaller one it holds when it failed: a crown can pass
    colour without passing nms); the second stage (models with one); the texture test (a detection)."""
    def centred(items, box):
        return any(abs(c[1] - box.x_center) <= box.width / 2.0 and abs(c[2] - box.y_center) <= box.height / 2.0
                   for c in items)
    windows = []
    for plan, scores in trace["maps"]:
        rows, cols = np.nonzero(scores > settings_threshold)
        for row, col in zip(rows.tolist(), cols.tolist()):
            x0, y0 = plan.window_origin(row, col)
            windows.append((0.0, x0 + plan.window / 2.0, y0 + plan.window / 2.0, plan.window))
    stages = {"svm": windows, "peak": trace["peaks"], "cap": trace["capped"], "nms": trace["nms"],
              "colour": trace["colour"], "cnn": trace["cnn"], "second": trace["second"]}
    return {name: sum(1 for box in truths if centred(items, box)) for name, items in stages.items()}


def evaluate_frames(model: TreeModel, frames: Sequence[dataset.Frame], settings: dict | None = None,
                    hull: bool = False, crown_px: float | str | None = None, funnel: bool = False) -> dict:
    """Frame-level figures of the detector on annotated frames (see the module docstring).

    hull: score only inside each frame's annotated area (detections outside it are ignored); crown_px: see
    frame_window_sizes; funnel: also count the crowns surviving each stage. Also returned: the detections'
    scores with hit flags (a precision-recall curve) and the false alarms centred on look-alike boxes."""
    settings = settings or detector_core.DetectorSettings()
    detectors = {}
    n_hits = n_fp = n_miss = n_lookalike = 0
    errors, scored = [], []
    stages = dict((name, 0) for name in FUNNEL_STAGES)
    domains_used = {}
    for frame in frames:
        windows = frame_window_sizes(model, frame, crown_px)
        if windows not in detectors:
            detectors[windows] = detector_core.TreeDetector(model, _with_windows(settings, windows))
        detector = detectors[windows]
        trace = {} if funnel else None
        value = cv2.extractChannel(frame.hsv, 2)
        maps = detector.score_maps(value)
        detections = detector.detections_from_maps(maps, frame.hsv, value, trace)
        name = model.domains[detector.domain_index].name
        domains_used[name] = domains_used.get(name, 0) + 1
        truths = frame.trees(model.species)
        if hull:
            detections = [d for d in detections if frame.in_area(d.x, d.y)]
        hits, false_positives, misses = match_detections(detections, truths)
        n_hits += len(hits)
        n_fp += len(false_positives)
        n_miss += len(misses)
        lookalikes = [b for b in frame.boxes if b.label and b.label != model.species]
        n_lookalike += sum(1 for d in false_positives if any(
            abs(d.x - b.x_center) <= b.width / 2.0 and abs(d.y - b.y_center) <= b.height / 2.0 for b in lookalikes))
        errors.extend(math.hypot(d.x - t.x_center, d.y - t.y_center) for d, t in hits)
        hit_ids = set(id(d) for d, _t in hits)
        scored.extend((d.score, id(d) in hit_ids) for d in detections)
        if funnel:
            counts = _funnel(trace, truths, detector.threshold("svm_threshold"))
            counts["texture"] = len(hits)
            for name_ in FUNNEL_STAGES:
                stages[name_] += counts[name_]
    result = _figures(n_hits, n_fp, n_miss, errors, len(frames), n_lookalike)
    result.update(scored=scored, domains=domains_used)
    if funnel:
        result["funnel"] = stages
    return result


def _with_windows(settings, windows):
    if windows is None:
        return settings
    copy = detector_core.DetectorSettings(
        svm_threshold=settings.svm_threshold, variance_threshold=settings.variance_threshold,
        hs_threshold=settings.hs_threshold, window_sizes=windows, step=settings.step,
        nms_overlap=settings.nms_overlap, max_detections=settings.max_detections, smoothing=settings.smoothing,
        edge_threshold=settings.edge_threshold, domain=settings.domain, second_threshold=settings.second_threshold,
        cnn_threshold=settings.cnn_threshold)
    return copy


def _figures(n_hits, n_fp, n_miss, errors, n_frames, n_lookalike):
    precision = n_hits / (n_hits + n_fp) if n_hits + n_fp else 0.0
    recall = n_hits / (n_hits + n_miss) if n_hits + n_miss else 0.0
    return {
        "precision": precision, "recall": recall,
        "f1": 2 * precision * recall / (precision + recall) if precision + recall else 0.0,
        "n_frames": n_frames, "n_trees": n_hits + n_miss, "n_detections": n_hits + n_fp,
        "n_hits": n_hits, "n_false_alarms": n_fp, "n_lookalike_false_alarms": n_lookalike,
        "false_alarms_per_image": n_fp / float(max(1, n_frames)),
        "lookalike_false_alarms_per_image": n_lookalike / float(max(1, n_frames)),
        "centre_error_px_mean": float(np.mean(errors)) if errors else None,
        "centre_error_px_median": float(np.median(errors)) if errors else None,
        "centre_error_px_p90": float(np.percentile(errors, 90)) if errors else None,
        "centre_errors": [float(e) for e in errors],
    }


def combine(results: Sequence[dict]) -> dict:
    """Pooled figures of several evaluate_frames results (hits, false alarms and misses added up)."""
    hits = sum(r["n_hits"] for r in results)
    false_alarms = sum(r["n_false_alarms"] for r in results)
    misses = sum(r["n_trees"] - r["n_hits"] for r in results)
    errors = [e for r in results for e in r["centre_errors"]]
    lookalikes = sum(r["n_lookalike_false_alarms"] for r in results)
    return _figures(hits, false_alarms, misses, errors, sum(r["n_frames"] for r in results), lookalikes)


def precision_recall_curve(scored: Sequence[tuple], n_trees: int) -> list[tuple[float, float, float]]:
    """[(score threshold, precision, recall)] over the detections' scores (best first)."""
    points = []
    hits = 0
    for index, (score, hit) in enumerate(sorted(scored, key=lambda item: -item[0]), start=1):
        hits += hit
        points.append((score, hits / float(index), hits / float(max(1, n_trees))))
    return points
