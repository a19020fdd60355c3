"""Training a detector model from annotated frames (pure: frames + seed in, TreeModel out).

1. Positives: every complete tree of the species, window = crown x margin, with size jitter (so one window
   size covers the gap to the next), a little centre jitter and the 8 rotations/mirrors (trees seen from
   above have no preferred orientation).
2. Negatives: boxes of other labels (look-alike palms, roofs, road crossings), windows shifted off a tree by
   35-60 % of W (incomplete trees, as the paper's negatives), windows of the wrong size on a tree, and
   random background windows.
3. A linear SVM (host_tools.detection.svm), then hard-negative mining: the detector's own score maps on
   the training frames give the false alarms of the current model, which are added and the SVM retrained.
4. Colour template = mean normalised hue and saturation histograms of the positives. The SVM, colour and
   variance thresholds are chosen together on crop-protocol windows of frames held back from the SVM
   (best accuracy with recall >= MIN_RECALL).
"""
import cv2
import numpy as np

from host_tools.detection import dataset, evaluation
from host_tools.detection.svm import train_linear_svm

import foranav_detector as detector_core
import foranav_features as features
from foranav_model import TreeModel

DEFAULT_WINDOW_SIZES = (96, 120, 144, 168)  # at 352 px frame width, margin 1.3: crowns of about 60-155 px
DEFAULT_REFERENCE_WIDTH = 352
DEFAULT_MARGIN = 1.3  # window side / crown diameter: the crown plus a ring of ground (its outline)
SIZE_JITTER = 1.2  # positives drawn at crown x margin x [1/J, J]: covers the gaps between window sizes
CENTRE_JITTER = 0.05  # of W, standard deviation (clipped at 2.5 sigma): a complete tree need not be centred
POSITIVE_COPIES = 4  # augmented copies per tree
SHIFTED_PER_TREE = 3
LOOKALIKE_COPIES = 4  # windows per look-alike object (other species, roofs, road crossings)
BACKGROUND_PER_FRAME = 6
HARD_NEGATIVE_ROUNDS = 3
HARD_NEGATIVES_PER_FRAME = 10
HARD_NEGATIVE_SCORE = -0.5  # windows scoring above this (and not a tree) are mined
SVM_C = 1.0
CALIBRATION_SPLIT = 0.2  # fraction of the frames held back to choose the thresholds
CALIBRATION_CROPS = 200  # of each class
MIN_RECALL = 0.97  # calibrated crop recall at least this (paper: 96.06 %)
SVM_THRESHOLDS = (-1.5, -1.2, -1.0, -0.8, -0.6, -0.45, -0.3, -0.15, 0.0, 0.15, 0.3)
CUE_QUANTILES = (0.0, 0.01, 0.02, 0.03, 0.05, 0.08, 0.12)
EDGE_THRESHOLDS = (-1.0, -0.5, 0.0, 0.5)  # candidates for the frame-edge test, searched on whole frames


def train(frames, species, seed=0, window_sizes=DEFAULT_WINDOW_SIZES, reference_width=DEFAULT_REFERENCE_WIDTH,
          margin=DEFAULT_MARGIN, log=None, crops=(), mining_windows=None):
    """Train a TreeModel for `species` from annotated frames. Same inputs and seed -> same model.

    The frames are split (seeded): the SVM learns from CALIBRATION_SPLIT's complement, and the three
    thresholds are chosen on the held-back frames' crop-protocol windows, so that they see honest SVM scores.
    crops: [(bgr, is positive)] ready-made windows added to the SVM's examples. mining_windows(frame, margin)
    -> window sizes for hard-negative mining on that frame (default: the model's, scaled to its width).
    """
    log = log or (lambda message: None)
    rng = np.random.RandomState(seed)
    order = rng.permutation(len(frames))
    n_calibration = int(round(CALIBRATION_SPLIT * len(frames))) if len(frames) >= 10 else 0
    calibration = [frames[i] for i in sorted(order[:n_calibration])]
    learning = [frames[i] for i in sorted(order[n_calibration:])]
    positives = _positive_descriptors(learning, species, margin, rng)
    if len(positives) == 0:
        raise ValueError("no complete '%s' trees in the training data" % species)
    negatives = _negative_descriptors(learning, species, margin, rng)
    if crops:  # ready-made windows (image, is positive): each image is one window
        crop_positives, crop_negatives = _crop_descriptors(crops, rng)
        positives = np.vstack([positives, crop_positives])
        negatives = np.vstack([negatives, crop_negatives])
    if len(negatives) == 0:
        raise ValueError("no negative windows in the training data")
    log("%d frames to learn from, %d to calibrate on; positives %d, negatives %d"
        % (len(learning), len(calibration), len(positives), len(negatives)))
    template_hue, template_sat = _colour_template(learning, species, margin)
    model = TreeModel(
        species=species, svm_weights=np.zeros(features.hog_descriptor_length()), svm_bias=0.0, svm_threshold=0.0,
        variance_threshold=0.0, hs_threshold=-1.0, template_hue=template_hue, template_sat=template_sat,
        window_sizes=window_sizes, window_margin=margin, reference_width=reference_width, seed=seed)
    for round_index in range(HARD_NEGATIVE_ROUNDS + 1):
        x = np.vstack([positives, negatives])
        y = np.concatenate([np.ones(len(positives)), -np.ones(len(negatives))])
        model.svm_weights, model.svm_bias = train_linear_svm(x, y, c=SVM_C, seed=seed + round_index)
        if round_index == HARD_NEGATIVE_ROUNDS:
            break
        hard = _hard_negatives(learning, species, model, rng, mining_windows)
        log("round %d: %d hard negatives" % (round_index + 1, len(hard)))
        if len(hard) == 0:
            break
        negatives = np.vstack([negatives, hard])
    _calibrate(model, calibration or learning, rng, log)
    if mining_windows is None:  # frames of one camera: the model's window sizes fit them
        _calibrate_edge(model, calibration or learning, log)
    else:  # per-image window sizes (real imagery): whole-frame detection is not the model's; keep the default
        log("edge test: per-image window sizes, default threshold %.2f kept" % model.edge_threshold)
    model.notes = ("species %s; %d frames (%d calibration); %d positives, %d negatives; seed %d"
                   % (species, len(frames), len(calibration), len(positives), len(negatives), seed))
    model.validate()
    return model


def _calibrate(model, frames, rng, log):
    """Choose the SVM, colour and variance thresholds on the crop-protocol windows of held-back frames:
    the best balanced accuracy among the settings whose recall is at least MIN_RECALL (the paper's figure plus a
    margin); the SVM threshold is searched near 0 only, the colour and variance thresholds over low
    quantiles of the positives (they exist to reject look-alikes, not trees)."""
    crops = evaluation.sample_frame_crops(frames, model.species, model.window_margin, CALIBRATION_CROPS,
                                          CALIBRATION_CROPS, int(rng.randint(1 << 30)), copies=3)
    labels = np.array([c[4] for c in crops], bool)
    if labels.all() or not labels.any():
        raise ValueError("calibration needs complete '%s' trees and other windows" % model.species)
    cues = np.array([evaluation.classify_window(model, f.value[r, c], f.hsv[r, c], None,
                                                features.window_with_context(f.value, cx - side / 2.0,
                                                                             cy - side / 2.0, side))[1:]
                     for f, cx, cy, side, _positive in crops
                     for r, c in [dataset.pixel_window(f, cx, cy, side)]])
    scores, similarities, variances = cues[:, 0], cues[:, 1], cues[:, 2]
    best = None
    for svm in SVM_THRESHOLDS:
        for hs_q in CUE_QUANTILES:
            hs = _below_quantile(similarities[labels], hs_q)
            for var_q in CUE_QUANTILES:
                var = _below_quantile(variances[labels], var_q)
                predicted = (scores > svm) & (similarities > hs) & (variances > var)
                recall = (predicted & labels).sum() / float(labels.sum())
                accuracy = 0.5 * (recall + (~predicted & ~labels).sum() / float((~labels).sum()))  # balanced
                key = (recall >= MIN_RECALL, accuracy, recall, -abs(svm))
                if best is None or key > best[0]:
                    best = (key, svm, hs, var)
    log("calibration positives %d, negatives %d; positive SVM scores 2/5/10 %% quantiles %s"
        % (labels.sum(), (~labels).sum(), np.round(np.percentile(scores[labels], [2, 5, 10]), 2)))
    (_ok, accuracy, recall, _svm), model.svm_threshold, model.hs_threshold, model.variance_threshold = best
    log("calibration on %d crops: accuracy %.3f recall %.3f at svm %.2f, hs %.3f, var %.4g"
        % (len(crops), accuracy, recall, model.svm_threshold, model.hs_threshold, model.variance_threshold))


def _calibrate_edge(model, frames, log):
    """Choose the frame-edge test (detector_core.DetectorSettings.edge_threshold) on whole held-back frames:
    the best detection F1, ties to the more permissive value. Crops cannot tell it: it is about where a
    window sits in the frame. Off is a candidate too, stored as the calibrated SVM threshold (no effect)."""
    best = None
    for edge in (model.svm_threshold,) + EDGE_THRESHOLDS:
        result = evaluation.evaluate_frames(model, frames, detector_core.DetectorSettings(edge_threshold=edge))
        key = (round(result["f1"], 6), -edge)
        if best is None or key > best[0]:
            best = (key, edge, result)
    _key, model.edge_threshold, result = best
    log("edge test on %d frames: threshold %.2f, detection precision %.3f recall %.3f F1 %.3f"
        % (len(frames), model.edge_threshold, result["precision"], result["recall"], result["f1"]))


def _below_quantile(values, quantile):
    """A threshold just below the given quantile of the values (0 -> just below the smallest)."""
    values = np.sort(values)
    index = int(np.floor(quantile * len(values)))
    upper = values[min(index, len(values) - 1)]
    lower = values[index - 1] if index > 0 else upper - max(abs(upper) * 0.05, 1e-9)
    return float(0.5 * (upper + lower))


def _positive_descriptors(frames, species, margin, rng):
    out = []
    for frame in frames:
        for box in frame.trees(species):
            base = dataset.crown_size(box) * margin
            for copy in range(POSITIVE_COPIES):
                side = base * np.exp(rng.uniform(-np.log(SIZE_JITTER), np.log(SIZE_JITTER))) if copy else base
                dx, dy = np.clip(rng.normal(0, CENTRE_JITTER, 2), -2.5 * CENTRE_JITTER, 2.5 * CENTRE_JITTER) * side
                cx, cy = box.x_center + dx, box.y_center + dy
                if side >= features.HOG_WINDOW and frame.window_fits(cx, cy, side):
                    out.append(dataset.top_descriptor(frame, cx, cy, side, transform=rng.randint(8)))
    return np.array(out, np.float32).reshape(-1, features.hog_descriptor_length())


def _crop_descriptors(crops, rng):
    """Descriptors of crop images (each one window; positives in 4 of their 8 rotations/mirrors)."""
    positives, negatives = [], []
    for bgr, positive in crops:
        value = cv2.extractChannel(features.bgr_to_hsv(bgr), 2)
        small = cv2.resize(value, (features.HOG_WINDOW, features.HOG_WINDOW), interpolation=cv2.INTER_AREA)
        for transform in (rng.permutation(8)[:4] if positive else [rng.randint(8)]):
            turned = np.rot90(small, transform % 4)
            turned = turned[:, ::-1] if transform >= 4 else turned
            (positives if positive else negatives).append(features.top_layer_hog(np.ascontiguousarray(turned)))
    length = features.hog_descriptor_length()
    return (np.array(positives, np.float32).reshape(-1, length), np.array(negatives, np.float32).reshape(-1, length))


def _negative_descriptors(frames, species, margin, rng):
    out = []
    for frame in frames:
        for cx, cy, side in _negative_windows(frame, species, margin, rng):
            out.append(dataset.top_descriptor(frame, cx, cy, side, transform=rng.randint(8)))
    return np.array(out, np.float32).reshape(-1, features.hog_descriptor_length())


def _negative_windows(frame, species, margin, rng):
    windows = []
    for box in frame.boxes:
        if not box.label:
            continue
        base = dataset.crown_size(box) * margin
        if box.label != species:  # look-alikes: the object framed like a tree would be
            for _ in range(LOOKALIKE_COPIES):
                windows.append((box.x_center, box.y_center, base * rng.uniform(0.85, 1.2)))
            continue
        angle = rng.uniform(0, 2 * np.pi)  # a near miss: sharpens the score peak on the crown centre
        shift = rng.uniform(0.25, 0.35) * base
        windows.append((box.x_center + shift * np.cos(angle), box.y_center + shift * np.sin(angle), base))
        for _ in range(SHIFTED_PER_TREE):  # incomplete trees: the window cuts the crown
            angle = rng.uniform(0, 2 * np.pi)
            shift = rng.uniform(0.35, 0.6) * base
            windows.append((box.x_center + shift * np.cos(angle), box.y_center + shift * np.sin(angle), base))
        windows.append((box.x_center, box.y_center, base * rng.uniform(0.45, 0.6)))  # inside the crown
        angle = rng.uniform(0, 2 * np.pi)  # most of the crown in a too small, off-centre window (as at an edge)
        side, shift = base * rng.uniform(0.6, 0.72), rng.uniform(0.2, 0.3) * base
        windows.append((box.x_center + shift * np.cos(angle), box.y_center + shift * np.sin(angle), side))
        windows.append((box.x_center, box.y_center, base * rng.uniform(1.7, 2.2)))  # tree small in window
    lo, hi = features.HOG_WINDOW * 2, min(frame.width, frame.height)
    for _ in range(BACKGROUND_PER_FRAME):
        side = rng.uniform(lo, hi) if hi > lo else lo
        windows.append((rng.uniform(side / 2, frame.width - side / 2), rng.uniform(side / 2, frame.height - side / 2),
                        side))
    return [(cx, cy, side) for cx, cy, side in windows
            if side >= features.HOG_WINDOW and frame.window_fits(cx, cy, side)
            and not dataset.is_tree_window(frame, species, cx, cy, side, margin, 0.18, 1.6)]


def _windows(frames, margin, wanted):
    """(frame, rows, cols) of the crown windows of complete boxes whose label is wanted."""
    for frame in frames:
        for box in frame.boxes:
            if wanted(box.label) and frame.complete(box):
                side = dataset.crown_size(box) * margin
                if side >= features.HOG_WINDOW and frame.window_fits(box.x_center, box.y_center, side):
                    rows, cols = dataset.pixel_window(frame, box.x_center, box.y_center, side)
                    yield frame, rows, cols


def _colour_template(frames, species, margin):
    """Mean normalised hue and saturation histograms of the colour regions of the species' crown windows."""
    hue_sum = np.zeros(features.HS_BINS)
    sat_sum = np.zeros(features.HS_BINS)
    count = 0
    for frame, rows, cols in _windows(frames, margin, lambda label: label == species):
        hue, sat = features.hs_histograms(features.colour_region(frame.hsv[rows, cols]))
        hue_sum += hue / hue.sum()
        sat_sum += sat / sat.sum()
        count += 1
    if count == 0:
        raise ValueError("no complete '%s' trees whose window fits the frame" % species)
    return (hue_sum / count).astype(np.float32), (sat_sum / count).astype(np.float32)


def _hard_negatives(frames, species, model, rng, mining_windows=None):
    """Windows the current model scores above HARD_NEGATIVE_SCORE that are not trees of the species."""
    out = []
    for frame in frames:
        windows = mining_windows(frame, model.window_margin) if mining_windows else None
        if mining_windows and not windows:
            continue
        detector = detector_core.TreeDetector(model, detector_core.DetectorSettings(window_sizes=windows))
        found = []
        for plan, scores in detector.score_maps(frame.value):
            rows, cols = np.nonzero(scores > HARD_NEGATIVE_SCORE)
            for row, col in zip(rows.tolist(), cols.tolist()):
                x0, y0 = plan.window_origin(row, col)
                cx, cy = x0 + plan.window / 2.0, y0 + plan.window / 2.0
                if not dataset.is_tree_window(frame, species, cx, cy, plan.window, model.window_margin, 0.25, 1.6):
                    found.append((float(scores[row, col]), cx, cy, plan.window))
        if len(found) > HARD_NEGATIVES_PER_FRAME:
            found.sort(key=lambda f: -f[0])
            keep = found[:HARD_NEGATIVES_PER_FRAME // 2]
            rest = found[HARD_NEGATIVES_PER_FRAME // 2:]
            picks = rng.choice(len(rest), HARD_NEGATIVES_PER_FRAME - len(keep), replace=False)
            found = keep + [rest[i] for i in sorted(picks)]
        for _score, cx, cy, side in found:
            out.append(dataset.top_descriptor(frame, cx, cy, side))
    return np.array(out, np.float32).reshape(-1, features.hog_descriptor_length())
