"""Training a detector model from annotated imageries (pure: frames + seed in, TreeModel out).

An imagery is the frames of one training CSV (one camera, light and place). The model holds one shared SVM
and, per imagery with trees of the species (a "domain"), a colour model and the three thresholds.

1. Positives: every complete tree of the species, window = crown x margin, with size jitter (so one window
   size covers the gap to the next), a little centre jitter and the 8 rotations/mirrors (trees seen from
   above have no preferred orientation).
2. Negatives: boxes of other labels (look-alike palms, roofs, road crossings), windows shifted off a tree by
   35-60 % of W (incomplete trees, as the paper's negatives), windows of the wrong size on a tree, and
   random background windows (survey imagery: at its crown scale, inside the annotated area).
3. A linear SVM (host_tools.detection.svm), then hard-negative mining: the detector's own score maps on
   the training frames give the false alarms of the current model, which are added and the SVM retrained.
   Flight-camera frames (reference_width wide) are mined with the model's window sizes; survey imagery at
   its own crown sizes and only inside each frame's annotated area (sites that annotate one block).
4. Per domain: the colour model (the mean hue and saturation histograms of its crowns, K templates, or a
   linear classifier), and the SVM, colour and variance thresholds chosen together on crop-protocol windows
   of its frames held back from the SVM (best balanced accuracy with recall >= MIN_RECALL).
5. Whole frames: the edge test on held-back camera frames; the window/crown ratios (detection at a given
   crown size) on held-back survey frames (best frame F1).
"""
from dataclasses import dataclass

import cv2
import numpy as np

from host_tools.detection import dataset, evaluation
from host_tools.detection.svm import train_linear_svm

import foranav_detector as detector_core
import foranav_features as features
from foranav_model import Domain, TreeModel

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
CROWN_RATIO_CENTRES = (0.9, 1.0, 1.1, 1.2, 1.3, 1.4, 1.5)  # window / crown, searched on whole survey frames
CROWN_RATIO_SPREAD = (0.85, 1.0, 1.18)  # three window sizes around each centre (crowns vary in a frame)
COLOUR_SVM_C = 0.1
SURVEY_BACKGROUND_SCALE = (0.8, 1.25)  # survey background windows: the imagery's window size x this


@dataclass
class Imagery:
    """One imagery (a training CSV): its frames share a camera, light and place, so one colour model."""
    name: str
    frames: list
    source: str = ""


def as_imageries(data):
    """A list of Imagery, or of frames (one imagery named 'default')."""
    data = list(data)
    if data and not isinstance(data[0], Imagery):
        return [Imagery("default", data)]
    return data


def is_camera_imagery(imagery, reference_width):
    """Frames of the flight camera (the model's reference width): the model's window sizes fit them."""
    return all(f.width == reference_width for f in imagery.frames)


def calibration_count(n_frames):
    """Frames held back per imagery: a fifth; one of a small imagery (3-9 frames); none below 3."""
    if n_frames >= 10:
        return int(round(CALIBRATION_SPLIT * n_frames))
    return 1 if n_frames >= 3 else 0


def train(data, species, seed=0, window_sizes=DEFAULT_WINDOW_SIZES, reference_width=DEFAULT_REFERENCE_WIDTH,
          margin=DEFAULT_MARGIN, log=None, crops=(), colour_kind="templates", colour_templates=1, provenance=""):
    """Train a TreeModel for `species` from annotated imageries (or frames). Same inputs and seed -> same model.

    Each imagery's frames are split (seeded): the SVM learns from CALIBRATION_SPLIT's complement, and the
    imagery's thresholds are chosen on its held-back frames' crop-protocol windows, so that they see honest
    SVM scores. An imagery without trees of the species only adds negatives. crops: [(bgr, is positive)]
    ready-made windows added to the SVM's examples. Frames of the flight camera (reference_width wide) are
    mined with the model's window sizes; survey imagery at its own crown sizes, inside each frame's
    annotated area.
    """
    log = log or (lambda message: None)
    imageries = as_imageries(data)
    if colour_kind not in features.COLOUR_KINDS:
        raise ValueError("colour model must be one of %s" % ", ".join(features.COLOUR_KINDS))
    rng = np.random.RandomState(seed)
    learning, calibration = {}, {}
    for imagery in imageries:
        order = rng.permutation(len(imagery.frames))
        n_calibration = calibration_count(len(imagery.frames))
        calibration[imagery.name] = [imagery.frames[i] for i in sorted(order[:n_calibration])]
        learning[imagery.name] = [imagery.frames[i] for i in sorted(order[n_calibration:])]
    camera = {im.name: is_camera_imagery(im, reference_width) for im in imageries}
    positives = np.vstack([_positive_descriptors(learning[im.name], species, margin, rng) for im in imageries])
    if len(positives) == 0:
        raise ValueError("no complete '%s' trees in the training data" % species)
    negatives = np.vstack([_negative_descriptors(learning[im.name], species, margin, rng, not camera[im.name])
                           for im in imageries])
    if crops:  # ready-made windows (image, is positive): each image is one window
        crop_positives, crop_negatives = _crop_descriptors(crops, rng)
        positives = np.vstack([positives, crop_positives])
        negatives = np.vstack([negatives, crop_negatives])
    if len(negatives) == 0:
        raise ValueError("no negative windows in the training data")
    log("%d frames to learn from, %d to calibrate on; positives %d, negatives %d"
        % (sum(len(f) for f in learning.values()), sum(len(f) for f in calibration.values()), len(positives),
           len(negatives)))
    targets = [im for im in imageries if any(f.trees(species) for f in learning[im.name])]
    domains = []
    for imagery in targets:
        vectors, bias = _colour_model(learning[imagery.name], species, margin, colour_kind, colour_templates, rng,
                                      not camera[imagery.name])
        frame_colour = np.mean([features.frame_colour(f.hsv) for f in imagery.frames], axis=0)
        domains.append(Domain(imagery.name, 0.0, -1.0, 0.0, vectors, bias, frame_colour))
    model = TreeModel(
        species=species, svm_weights=np.zeros(features.hog_descriptor_length()), svm_bias=0.0, domains=domains,
        colour_kind=colour_kind, window_sizes=window_sizes, window_margin=margin, reference_width=reference_width,
        seed=seed, provenance=provenance)
    for round_index in range(HARD_NEGATIVE_ROUNDS + 1):
        x = np.vstack([positives, negatives])
        y = np.concatenate([np.ones(len(positives)), -np.ones(len(negatives))])
        model.svm_weights, model.svm_bias = train_linear_svm(x, y, c=SVM_C, seed=seed + round_index)
        if round_index == HARD_NEGATIVE_ROUNDS:
            break
        hard = np.vstack([_hard_negatives(learning[im.name], species, model, rng, not camera[im.name])
                          for im in imageries])
        log("round %d: %d hard negatives" % (round_index + 1, len(hard)))
        if len(hard) == 0:
            break
        negatives = np.vstack([negatives, hard])
    for index, imagery in enumerate(targets):
        _calibrate(model, index, calibration[imagery.name] or learning[imagery.name], rng, log)
    camera_targets = [im for im in targets if camera[im.name]]
    survey_targets = [im for im in targets if not camera[im.name]]
    if camera_targets:  # frames of one camera: the model's window sizes fit them
        _calibrate_edge(model, [(im.name, calibration[im.name] or learning[im.name]) for im in camera_targets], log)
    else:  # survey imagery: a crown cut by the edge is still annotated; keep the default
        log("edge test: survey imagery, default threshold %.2f kept" % model.edge_threshold)
    if survey_targets:
        _calibrate_frames(model, [(im.name, calibration[im.name] or learning[im.name]) for im in survey_targets],
                          log)
    else:
        crowns = [dataset.crown_size(b) for im in camera_targets for f in im.frames for b in f.trees(species)]
        model.crown_ratios = tuple(round(w / float(np.median(crowns)), 4) for w in window_sizes)
    model.notes = ("species %s; %d frames (%d calibration) of %d imageries (%s); %d positives, %d negatives; seed %d"
                   % (species, sum(len(im.frames) for im in imageries), sum(len(f) for f in calibration.values()),
                      len(imageries), ", ".join(im.name for im in imageries), len(positives), len(negatives), seed))
    model.validate()
    return model


def _calibrate(model, domain_index, frames, rng, log):
    """Choose one imagery's SVM, colour and variance thresholds on the crop-protocol windows of its held-back
    frames: the best balanced accuracy among the settings whose recall is at least MIN_RECALL (the paper's
    figure plus a margin); the SVM threshold is searched near 0 only, the colour and variance thresholds
    over low quantiles of the positives (they exist to reject look-alikes, not trees)."""
    domain = model.domains[domain_index]
    crops = evaluation.sample_frame_crops(frames, model.species, model.window_margin, CALIBRATION_CROPS,
                                          CALIBRATION_CROPS, int(rng.randint(1 << 30)), copies=3)
    labels = np.array([c[4] for c in crops], bool)
    if labels.all() or not labels.any():
        raise ValueError("calibration of imagery %s needs complete '%s' trees and other windows"
                         % (domain.name, model.species))
    cues = np.array([evaluation.frame_window_cues(model, domain_index, f, cx, cy, side)
                     for f, cx, cy, side, _positive in crops])
    scores, similarities, variances = cues[:, 0], cues[:, 1], cues[:, 2]
    best = None
    for svm in SVM_THRESHOLDS:
        for hs_q in CUE_QUANTILES:
            hs = _below_quantile(similarities[labels], hs_q)
            for var_q in CUE_QUANTILES:
                var = _below_quantile(variances[labels], var_q)
                predicted = detector_core.passes_thresholds(scores, similarities, variances, svm, hs, var)
                recall = (predicted & labels).sum() / float(labels.sum())
                accuracy = 0.5 * (recall + (~predicted & ~labels).sum() / float((~labels).sum()))  # balanced
                key = (recall >= MIN_RECALL, accuracy, recall, -abs(svm))
                if best is None or key > best[0]:
                    best = (key, svm, hs, var)
    log("%s: calibration positives %d, negatives %d; positive SVM scores 2/5/10 %% quantiles %s"
        % (domain.name, labels.sum(), (~labels).sum(), np.round(np.percentile(scores[labels], [2, 5, 10]), 2)))
    (_ok, accuracy, recall, _svm), domain.svm_threshold, domain.hs_threshold, domain.variance_threshold = best
    log("%s: calibration on %d crops: accuracy %.3f recall %.3f at svm %.2f, colour %.3f, var %.4g"
        % (domain.name, len(crops), accuracy, recall, domain.svm_threshold, domain.hs_threshold,
           domain.variance_threshold))


def _calibrate_edge(model, imagery_frames, log):
    """Choose the frame-edge test (detector_core.DetectorSettings.edge_threshold) on whole held-back frames
    of the camera imageries [(name, frames)]: the best detection F1, ties to the more permissive value.
    Crops cannot tell it: it is about where a window sits in the frame. Off is a candidate too, stored as
    the first imagery's calibrated SVM threshold (no effect)."""
    best = None
    n_frames = sum(len(frames) for _name, frames in imagery_frames)
    for edge in (model.svm_threshold,) + EDGE_THRESHOLDS:
        totals = [evaluation.evaluate_frames(model, frames, detector_core.DetectorSettings(edge_threshold=edge,
                                                                                           domain=name))
                  for name, frames in imagery_frames]
        result = evaluation.combine(totals)
        key = (round(result["f1"], 6), -edge)
        if best is None or key > best[0]:
            best = (key, edge, result)
    _key, model.edge_threshold, result = best
    log("edge test on %d frames: threshold %.2f, detection precision %.3f recall %.3f F1 %.3f"
        % (n_frames, model.edge_threshold, result["precision"], result["recall"], result["f1"]))


def _calibrate_frames(model, imagery_frames, log):
    """Whole-frame calibration on the held-back survey frames [(name, frames)]: the window/crown ratios
    (shared) and each imagery's SVM threshold (the crop protocol's value or one of SVM_THRESHOLDS). Each
    frame is scanned at its own typical crown size (as a user's --crown-px) and scored inside its annotated
    area; the best mean frame F1 over the imageries wins, ties to the ratio nearest the training margin and
    the crop protocol's threshold. Score maps do not depend on the threshold: one scan per frame and ratio."""
    crop_thresholds = {d.name: d.svm_threshold for d in model.domains}
    best = None
    for centre in CROWN_RATIO_CENTRES:
        model.crown_ratios = tuple(round(centre * spread, 4) for spread in CROWN_RATIO_SPREAD)
        chosen, f1s = {}, []
        for name, frames in imagery_frames:
            candidates = sorted(set((crop_thresholds[name],) + SVM_THRESHOLDS))
            counts = dict((t, [0, 0, 0]) for t in candidates)  # hits, false alarms, misses
            for frame in frames:
                windows = evaluation.frame_window_sizes(model, frame, "boxes")
                scanner = detector_core.TreeDetector(model, detector_core.DetectorSettings(
                    window_sizes=windows, max_detections=None, domain=name))
                maps = scanner.score_maps(frame.value)
                for threshold in candidates:
                    detector = detector_core.TreeDetector(model, detector_core.DetectorSettings(
                        svm_threshold=threshold, window_sizes=windows, max_detections=None, domain=name))
                    detections = [d for d in detector.detections_from_maps(maps, frame.hsv, frame.value)
                                  if frame.in_area(d.x, d.y)]
                    hits, false_alarms, misses = evaluation.match_detections(detections, frame.trees(model.species))
                    for i, n in enumerate((len(hits), len(false_alarms), len(misses))):
                        counts[threshold][i] += n
            scored = [(_f1(*counts[t]), -abs(t - crop_thresholds[name]), t) for t in candidates]
            f1, _closeness, chosen[name] = max(scored)
            f1s.append(f1)
        key = (round(float(np.mean(f1s)), 6), -abs(centre - model.window_margin))
        log("crown ratios %s: frame F1 %s at SVM thresholds %s"
            % (", ".join("%.2f" % r for r in model.crown_ratios), ", ".join("%.3f" % f for f in f1s),
               ", ".join("%.2f" % chosen[name] for name, _frames in imagery_frames)))
        if best is None or key > best[0]:
            best = (key, model.crown_ratios, dict(chosen))
    _key, model.crown_ratios, chosen = best
    for name, threshold in chosen.items():
        model.domain(name).svm_threshold = threshold
    log("frames: crown ratios %s, SVM thresholds %s (mean frame F1 %.3f)"
        % (", ".join("%.2f" % r for r in model.crown_ratios),
           ", ".join("%s %.2f" % item for item in chosen.items()), best[0][0]))


def _f1(hits, false_alarms, misses):
    return 2.0 * hits / (2 * hits + false_alarms + misses) if hits else 0.0


def _colour_model(frames, species, margin, kind, templates, rng, survey):
    """(colour vectors, bias) of one imagery: K templates (K = 1: the mean histogram of the crowns' colour
    regions; more: seeded k-means of them), or a linear classifier of crowns against the imagery's other
    windows (look-alikes, windows cutting a crown, background)."""
    histograms = []
    for frame, rows, cols in _windows(frames, margin, lambda label: label == species):
        hue, sat = features.hs_histograms(features.colour_region(frame.hsv[rows, cols]))
        histograms.append(np.concatenate([hue / hue.sum(), sat / sat.sum()]))
    if not histograms:
        raise ValueError("no complete '%s' trees whose window fits the frame" % species)
    if kind == "templates" and (templates <= 1 or len(histograms) <= templates):
        total = np.zeros(2 * features.HS_BINS)
        for histogram in histograms:  # summed one by one in float64 (the mean is the same bytes every time)
            total += histogram
        return (total / len(histograms)).astype(np.float32)[None, :], 0.0
    histograms = np.array(histograms, np.float64)
    if kind == "templates":
        return _kmeans(histograms, templates, rng).astype(np.float32), 0.0
    positive = [features.colour_feature(*features.smoothed_hs(frame.hsv[rows, cols]))
                for frame, rows, cols in _windows(frames, margin, lambda label: label == species)]
    negative = []
    for frame in frames:
        for cx, cy, side in _negative_windows(frame, species, margin, rng, survey):
            rows, cols = dataset.pixel_window(frame, cx, cy, side)
            negative.append(features.colour_feature(*features.smoothed_hs(frame.hsv[rows, cols])))
    if not negative:
        raise ValueError("a linear colour model needs other windows than trees in the imagery")
    weights, bias = train_linear_svm(np.vstack([positive, negative]),
                                     np.concatenate([np.ones(len(positive)), -np.ones(len(negative))]),
                                     c=COLOUR_SVM_C, seed=int(rng.randint(1 << 30)))
    return weights[None, :], bias


def _kmeans(points, k, rng, iterations=25):
    """Seeded k-means (k-means++ start) of histogram vectors -> (k, d) centres."""
    centres = [points[rng.randint(len(points))]]
    for _ in range(1, k):
        distance = np.min([((points - c) ** 2).sum(axis=1) for c in centres], axis=0)
        centres.append(points[rng.choice(len(points), p=distance / distance.sum())])
    centres = np.array(centres)
    for _ in range(iterations):
        nearest = np.argmin([((points - c) ** 2).sum(axis=1) for c in centres], axis=0)
        centres = np.array([points[nearest == j].mean(axis=0) if (nearest == j).any() else centres[j]
                            for j in range(k)])
    return centres


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


def _negative_descriptors(frames, species, margin, rng, survey=False):
    out = []
    for frame in frames:
        for cx, cy, side in _negative_windows(frame, species, margin, rng, survey):
            out.append(dataset.top_descriptor(frame, cx, cy, side, transform=rng.randint(8)))
    return np.array(out, np.float32).reshape(-1, features.hog_descriptor_length())


def _negative_windows(frame, species, margin, rng, survey=False):
    """Negative windows of a frame. Survey imagery (survey=True): background at the imagery's crown scale
    and only inside the annotated area (outside it, trees are not labelled)."""
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
    if survey:
        lo = hi = frame.typical_crown() * margin
    for _ in range(BACKGROUND_PER_FRAME):
        if survey:
            side = lo * rng.uniform(*SURVEY_BACKGROUND_SCALE)
        else:
            side = rng.uniform(lo, hi) if hi > lo else lo
        windows.append((rng.uniform(side / 2, frame.width - side / 2), rng.uniform(side / 2, frame.height - side / 2),
                        side))
    return [(cx, cy, side) for cx, cy, side in windows
            if side >= features.HOG_WINDOW and frame.window_fits(cx, cy, side)
            and not dataset.is_tree_window(frame, species, cx, cy, side, margin, 0.18, 1.6)
            and (not survey or frame.in_area(cx, cy))]


def _windows(frames, margin, wanted):
    """(frame, rows, cols) of the crown windows of complete boxes whose label is wanted."""
    for frame in frames:
        for box in frame.boxes:
            if wanted(box.label) and frame.complete(box):
                side = dataset.crown_size(box) * margin
                if side >= features.HOG_WINDOW and frame.window_fits(box.x_center, box.y_center, side):
                    rows, cols = dataset.pixel_window(frame, box.x_center, box.y_center, side)
                    yield frame, rows, cols


def survey_windows(frame, margin):
    """Window sizes for mining a survey frame at its own crown scale: its crown sizes x margin, at most 3."""
    sizes = sorted({max(features.HOG_WINDOW, int(round(dataset.crown_size(b) * margin)))
                    for b in frame.boxes if b.label})
    if len(sizes) > 3:
        sizes = [sizes[len(sizes) // 10], sizes[len(sizes) // 2], sizes[(9 * len(sizes)) // 10]]
    return tuple(s for s in sizes if s <= min(frame.width, frame.height))


def _hard_negatives(frames, species, model, rng, survey=False):
    """Windows the current model scores above HARD_NEGATIVE_SCORE that are not trees of the species (survey
    imagery: at the frame's crown scale, inside its annotated area). Vectorised over each score map: a
    survey image holds hundreds of thousands of windows."""
    out = []
    for frame in frames:
        windows = survey_windows(frame, model.window_margin) if survey else None
        if survey and not windows:
            continue
        detector = detector_core.TreeDetector(model, detector_core.DetectorSettings(window_sizes=windows))
        area = _area_mask(frame) if survey else None
        found = []
        for plan, scores in detector.score_maps(frame.value):
            rows, cols = np.nonzero(scores > HARD_NEGATIVE_SCORE)
            unit = plan.stride * plan.lattice / plan.scale  # as plan.window_origin
            cx = cols * unit + plan.window / 2.0
            cy = rows * unit + plan.window / 2.0
            keep = ~dataset.tree_window_mask(frame, species, cx, cy, plan.window, model.window_margin, 0.25, 1.6)
            if area is not None:
                keep &= area[np.clip(cy.astype(int), 0, frame.height - 1), np.clip(cx.astype(int), 0, frame.width - 1)]
            values = scores[rows, cols].astype(np.float64)
            found.extend(zip(values[keep].tolist(), cx[keep].tolist(), cy[keep].tolist(),
                             [plan.window] * int(keep.sum())))
        if len(found) > HARD_NEGATIVES_PER_FRAME:
            found.sort(key=lambda f: -f[0])
            keep = found[:HARD_NEGATIVES_PER_FRAME // 2]
            rest = found[HARD_NEGATIVES_PER_FRAME // 2:]
            picks = rng.choice(len(rest), HARD_NEGATIVES_PER_FRAME - len(keep), replace=False)
            found = keep + [rest[i] for i in sorted(picks)]
        for _score, cx, cy, side in found:
            out.append(dataset.top_descriptor(frame, cx, cy, side))
    return np.array(out, np.float32).reshape(-1, features.hog_descriptor_length())


def _area_mask(frame):
    """Boolean image of the frame's annotated area (all False without labelled boxes)."""
    mask = np.zeros((frame.height, frame.width), np.uint8)
    area = frame.annotated_area()
    if area is not None:
        cv2.fillConvexPoly(mask, np.round(area.reshape(-1, 2)).astype(np.int32), 1)
    return mask.astype(bool)
