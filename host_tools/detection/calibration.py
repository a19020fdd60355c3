"""Threshold calibration of a trained model (steps 4-5 of host_tools.detection.training): per domain the SVM,
colour and variance thresholds together on crop-protocol windows of held-back frames; the frame-edge test
and the window/crown ratios on whole held-back frames."""
from collections.abc import Callable, Sequence

import numpy as np

from host_tools.detection import evaluation
from host_tools.detection.dataset import Frame

import foranav_detector as detector_core
from foranav_model import TreeModel

Log = Callable[[str], None]  # where progress lines go

CALIBRATION_CROPS = 200  # of each class
MIN_RECALL = 0.97  # calibrated crop recall at least this (paper: 96.06 %)
SVM_THRESHOLDS = (-1.5, -1.2, -1.0, -0.8, -0.6, -0.45, -0.3, -0.15, 0.0, 0.15, 0.3)
CUE_QUANTILES = (0.0, 0.01, 0.02, 0.03, 0.05, 0.08, 0.12)
EDGE_THRESHOLDS = (-1.0, -0.5, 0.0, 0.5)  # candidates for the frame-edge test, searched on whole frames
CROWN_RATIO_CENTRES = (0.9, 1.0, 1.1, 1.2, 1.3, 1.4, 1.5)  # window / crown, searched on whole survey frames
CROWN_RATIO_SPREAD = (0.85, 1.0, 1.18)  # three window sizes around each centre (crowns vary in a frame)


def calibrate(model: TreeModel, domain_index: int, frames: Sequence[Frame], rng: np.random.Generator,
              log: Log) -> None:
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
            hs = below_quantile(similarities[labels], hs_q)
            for var_q in CUE_QUANTILES:
                var = below_quantile(variances[labels], var_q)
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


def calibrate_edge(model: TreeModel, imagery_frames: Sequence[tuple[str, Sequence[Frame]]], log: Log) -> None:
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


def calibrate_frames(model: TreeModel, imagery_frames: Sequence[tuple[str, Sequence[Frame]]], log: Log) -> None:
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


def _f1(hits: int, false_alarms: int, misses: int) -> float:
    return 2.0 * hits / (2 * hits + false_alarms + misses) if hits else 0.0


def below_quantile(values: Sequence[float], quantile: float) -> float:
    """A threshold just below the given quantile of the values (0 -> just below the smallest)."""
    values = np.sort(values)
    index = int(np.floor(quantile * len(values)))
    upper = values[min(index, len(values) - 1)]
    lower = values[index - 1] if index > 0 else upper - max(abs(upper) * 0.05, 1e-9)
    return float(0.5 * (upper + lower))
