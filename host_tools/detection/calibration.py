"""Threshold calibration of a trained model (steps 4-5 of host_tools.detection.training): per domain the SVM,
colour and variance thresholds together on crop-protocol windows of held-back frames; the frame-edge test
and the window/crown ratios on whole held-back frames."""
from collections.abc import Callable, Sequence

import numpy as np

from host_tools.detection import dataset, evaluation
from host_tools.detection.dataset import Frame

import foranav_detector as detector_core
import foranav_features as features
from foranav_model import TreeModel

Log = Callable[[str], None]  # where progress lines go

CALIBRATION_CROPS = 200  # of each class
MIN_RECALL = 0.97  # calibrated crop recall at least this (paper: 96.06 %)
SVM_THRESHOLDS = (-1.5, -1.2, -1.0, -0.8, -0.6, -0.45, -0.3, -0.15, 0.0, 0.15, 0.3)
CUE_QUANTILES = (0.0, 0.01, 0.02, 0.03, 0.05, 0.08, 0.12)
SECOND_THRESHOLDS = (-1.0, -0.75, -0.5, -0.25, 0.0)  # second-stage thresholds searched (models with one)
CNN_THRESHOLDS = (-3.0, -2.0, -1.0, 0.0, 1.0, 2.0)  # network logits searched (models with one)
EDGE_THRESHOLDS = (-1.0, -0.5, 0.0, 0.5)  # candidates for the frame-edge test, searched on whole frames
CROWN_RATIO_CENTRES = (0.9, 1.0, 1.1, 1.2, 1.3, 1.4, 1.5)  # window / crown, searched on whole survey frames
CROWN_RATIO_SPREAD = (0.85, 1.0, 1.18)  # three window sizes around each centre (crowns vary in a frame)
# Survey imagery: the texture threshold stays below TEXTURE_CAP_MARGIN x the least textured training image's
# TEXTURE_CAP_QUANTILE of its crowns. The cue is gradient per pixel per unit of contrast, so it follows each
# image's sharpness and zoom: the Google Earth training images' crowns differ by 2.4x, and a threshold chosen
# on the sharpest one, held back, rejected every crown of the held-out image (docs/detector.md). The margin
# leaves room for an image blurrier than every training image.
TEXTURE_CAP_QUANTILE = 0.05
TEXTURE_CAP_MARGIN = 0.5


def calibrate(model: TreeModel, domain_index: int, frames: Sequence[Frame], rng: np.random.RandomState,
              log: Log, texture_cap: float | None = None) -> None:
    """Choose one imagery's SVM, colour and variance thresholds on the crop-protocol windows of its held-back
    frames: the best balanced accuracy among the settings whose recall is at least MIN_RECALL (the paper's
    figure plus a margin); the SVM threshold is searched near 0 only, the colour and variance thresholds
    over low quantiles of the positives (they exist to reject look-alikes, not trees), the variance
    threshold no higher than texture_cap when one is given."""
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
    has_second, has_cnn = model.second_window is not None, model.cnn_onnx is not None
    later = [evaluation.frame_later_scores(model, f, cx, cy, side) for f, cx, cy, side, _positive in crops]
    seconds = np.array([s if has_second else 0.0 for s, _logit in later])
    logits = np.array([logit if has_cnn else 0.0 for _s, logit in later])
    best = None
    for svm in SVM_THRESHOLDS:
        for hs_q in CUE_QUANTILES:
            hs = below_quantile(similarities[labels], hs_q)
            for var_q in CUE_QUANTILES:
                var = below_quantile(variances[labels], var_q)
                var = var if texture_cap is None else min(var, texture_cap)
                first = detector_core.passes_thresholds(scores, similarities, variances, svm, hs, var)
                for second in (SECOND_THRESHOLDS if has_second else (0.0,)):
                    for logit in (CNN_THRESHOLDS if has_cnn else (0.0,)):
                        predicted = first & (seconds > second) if has_second else first
                        predicted = predicted & (logits > logit) if has_cnn else predicted
                        recall = (predicted & labels).sum() / float(labels.sum())
                        accuracy = 0.5 * (recall + (~predicted & ~labels).sum() / float((~labels).sum()))  # balanced
                        key = (recall >= MIN_RECALL, accuracy, recall, -abs(svm), -abs(second), -abs(logit))
                        if best is None or key > best[0]:
                            best = (key, svm, hs, var, second, logit)
    log("%s: calibration positives %d, negatives %d; positive SVM scores 2/5/10 %% quantiles %s"
        % (domain.name, labels.sum(), (~labels).sum(), np.round(np.percentile(scores[labels], [2, 5, 10]), 2)))
    key, domain.svm_threshold, domain.hs_threshold, domain.variance_threshold, domain.second_threshold, \
        domain.cnn_threshold = best
    log("%s: calibration on %d crops: accuracy %.3f recall %.3f at svm %.2f, colour %.3f, var %.4g%s%s"
        % (domain.name, len(crops), key[1], key[2], domain.svm_threshold, domain.hs_threshold,
           domain.variance_threshold, ", second stage %.2f" % domain.second_threshold if has_second else "",
           ", network %.2f" % domain.cnn_threshold if has_cnn else ""))


def texture_cap(frames: Sequence[Frame], species: str, margin: float) -> float | None:
    """TEXTURE_CAP_MARGIN x the lowest, over the imagery's frames, of the TEXTURE_CAP_QUANTILE of the texture
    (foranav_features.hog_texture) of each frame's complete crowns, window = crown x margin; None without
    such crowns."""
    lowest = None
    for frame in frames:
        windows = [(box.x_center, box.y_center, dataset.crown_size(box) * margin) for box in frame.trees(species)]
        textures = [features.hog_texture(frame.value[dataset.pixel_window(frame, cx, cy, side)])
                    for cx, cy, side in windows if frame.window_fits(cx, cy, side)]
        if textures:
            quantile = float(np.percentile(textures, 100 * TEXTURE_CAP_QUANTILE))
            lowest = quantile if lowest is None else min(lowest, quantile)
    return None if lowest is None else TEXTURE_CAP_MARGIN * lowest


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


def calibrate_frames(model: TreeModel, imagery_frames: Sequence[tuple[str, Sequence[Frame]]], log: Log,
                     frame_done: Callable[[], None] = lambda: None) -> None:
    """Whole-frame calibration on the held-back survey frames [(name, frames)]: the window/crown ratios
    (shared) and each imagery's SVM threshold (the crop protocol's value or one of SVM_THRESHOLDS) with its
    second-stage threshold, or, for a model with a network, its network threshold (the second stage's then
    stays at the crop protocol's value). Each frame is scanned at its own typical crown size (as a user's
    --crown-px) and scored inside its annotated area; the best mean frame F1 over the imageries wins, ties to
    the ratio nearest the training margin and the crop protocol's thresholds. Score maps do not depend on the
    thresholds: one scan per frame and ratio."""
    best = None
    for centre in CROWN_RATIO_CENTRES:
        model.crown_ratios = tuple(round(centre * spread, 4) for spread in CROWN_RATIO_SPREAD)
        chosen, f1s = {}, []
        for name, frames in imagery_frames:
            candidates = _frame_candidates(model, model.domain(name))
            counts = dict((t, [0, 0, 0]) for t in candidates)  # hits, false alarms, misses
            for frame in frames:
                windows = evaluation.frame_window_sizes(model, frame, "boxes")
                detector = detector_core.TreeDetector(model, detector_core.DetectorSettings(
                    window_sizes=windows, max_detections=None, domain=name))
                maps = detector.score_maps(frame.value)  # once per frame; later stages' scores kept
                for thresholds in candidates:
                    settings = detector.settings
                    settings.svm_threshold, settings.second_threshold, settings.cnn_threshold = thresholds
                    detections = [d for d in detector.detections_from_maps(maps, frame.hsv, frame.value)
                                  if frame.in_area(d.x, d.y)]
                    hits, false_alarms, misses = evaluation.match_detections(detections, frame.trees(model.species))
                    for i, n in enumerate((len(hits), len(false_alarms), len(misses))):
                        counts[thresholds][i] += n
                frame_done()
            chosen[name] = max(candidates, key=lambda t: _f1(*counts[t]))  # the first of equals: nearest the crops'
            f1 = _f1(*counts[chosen[name]])
            f1s.append(f1)
        key = (round(float(np.mean(f1s)), 6), -abs(centre - model.window_margin))
        log("crown ratios %s: frame F1 %s at thresholds %s"
            % (", ".join("%.2f" % r for r in model.crown_ratios), ", ".join("%.3f" % f for f in f1s),
               ", ".join(_thresholds_text(chosen[name]) for name, _frames in imagery_frames)))
        if best is None or key > best[0]:
            best = (key, model.crown_ratios, dict(chosen))
    _key, model.crown_ratios, chosen = best
    for name, (svm, second, logit) in chosen.items():
        domain = model.domain(name)
        domain.svm_threshold = svm
        domain.second_threshold = domain.second_threshold if second is None else second
        domain.cnn_threshold = domain.cnn_threshold if logit is None else logit
    log("frames: crown ratios %s, thresholds %s (mean frame F1 %.3f)"
        % (", ".join("%.2f" % r for r in model.crown_ratios),
           ", ".join("%s %s" % (name, _thresholds_text(t)) for name, t in chosen.items()), best[0][0]))


def _frame_candidates(model: TreeModel, domain) -> list[tuple]:
    """(svm, second, network) thresholds to try on whole frames (None: the model has no such stage), those
    nearest the crop protocol's first: max() over equal F1 then keeps the first."""
    svms = sorted(set((domain.svm_threshold,) + SVM_THRESHOLDS), key=lambda t: abs(t - domain.svm_threshold))
    seconds, logits = [None], [None]
    if model.cnn_onnx is not None:
        logits = sorted(set((domain.cnn_threshold,) + CNN_THRESHOLDS), key=lambda t: abs(t - domain.cnn_threshold))
        seconds = [domain.second_threshold] if model.second_window is not None else [None]
    elif model.second_window is not None:
        seconds = sorted(set((domain.second_threshold,) + SECOND_THRESHOLDS),
                         key=lambda t: abs(t - domain.second_threshold))
    return [(svm, second, logit) for svm in svms for second in seconds for logit in logits]


def _thresholds_text(thresholds):
    """'-0.30', '-0.30/-0.50' (SVM / second stage) or '-0.30/-0.50/1.00' (and network)."""
    return "/".join("%.2f" % t for t in thresholds if t is not None)


def _f1(hits: int, false_alarms: int, misses: int) -> float:
    return 2.0 * hits / (2 * hits + false_alarms + misses) if hits else 0.0


def below_quantile(values: Sequence[float], quantile: float) -> float:
    """A threshold just below the given quantile of the values (0 -> just below the smallest)."""
    values = np.sort(values)
    index = int(np.floor(quantile * len(values)))
    upper = values[min(index, len(values) - 1)]
    lower = values[index - 1] if index > 0 else upper - max(abs(upper) * 0.05, 1e-9)
    return float(0.5 * (upper + lower))
