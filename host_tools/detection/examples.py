"""Training examples of a detector model (steps 1-3 of host_tools.detection.training): the descriptors of
positive windows (augmented), negative windows (look-alikes, shifted, wrongly sized, background), ready-made
crops and hard negatives mined with the current model, and each imagery's colour model."""
from collections.abc import Iterator, Sequence

import cv2
import numpy as np

from host_tools.detection import dataset
from host_tools.detection.dataset import Frame
from host_tools.detection.svm import train_linear_svm

import foranav_detector as detector_core
import foranav_colour as colours
import foranav_features as features
from foranav_model import TreeModel

SIZE_JITTER = 1.2  # positives drawn at crown x margin x [1/J, J]: covers the gaps between window sizes
CENTRE_JITTER = 0.05  # of W, standard deviation (clipped at 2.5 sigma): a complete tree need not be centred
POSITIVE_COPIES = 4  # augmented copies per tree
SHIFTED_PER_TREE = 3
LOOKALIKE_COPIES = 4  # windows per look-alike object (other species, roofs, road crossings)
BACKGROUND_PER_FRAME = 6
HARD_NEGATIVES_PER_FRAME = 10
SURVEY_HARD_NEGATIVES_PER_CROWN = 1.0  # survey frames hold tens to hundreds of crowns: mine in proportion
HARD_NEGATIVE_SCORE = -0.5  # windows scoring above this (and not a tree) are mined
COLOUR_SVM_C = 0.1
SURVEY_BACKGROUND_SCALE = (0.8, 1.25)  # survey background windows: the imagery's window size x this


def colour_model(frames: Sequence[Frame], species: str, margin: float, kind: str, templates: int,
                 rng: np.random.RandomState, survey: bool) -> tuple[np.ndarray, float]:
    """(colour vectors, bias) of one imagery: K templates (K = 1: the mean histogram of the crowns' colour
    regions; more: seeded k-means of them), or a linear classifier of crowns against the imagery's other
    windows (look-alikes, windows cutting a crown, background)."""
    histograms = []
    for frame, rows, cols in _windows(frames, margin, lambda label: label == species):
        hue, sat = colours.hs_histograms(colours.colour_region(frame.hsv[rows, cols]))
        histograms.append(np.concatenate([hue / hue.sum(), sat / sat.sum()]))
    if not histograms:
        raise ValueError("no complete '%s' trees whose window fits the frame" % species)
    if kind == "templates" and (templates <= 1 or len(histograms) <= templates):
        total = np.zeros(2 * colours.HS_BINS)
        for histogram in histograms:  # summed one by one in float64 (the mean is the same bytes every time)
            total += histogram
        return (total / len(histograms)).astype(np.float32)[None, :], 0.0
    histograms = np.array(histograms, np.float64)
    if kind == "templates":
        return _kmeans(histograms, templates, rng).astype(np.float32), 0.0
    positive = [colours.colour_feature(*colours.smoothed_hs(frame.hsv[rows, cols]))
                for frame, rows, cols in _windows(frames, margin, lambda label: label == species)]
    negative = []
    for frame in frames:
        for cx, cy, side in negative_windows(frame, species, margin, rng, survey):
            rows, cols = dataset.pixel_window(frame, cx, cy, side)
            negative.append(colours.colour_feature(*colours.smoothed_hs(frame.hsv[rows, cols])))
    if not negative:
        raise ValueError("a linear colour model needs other windows than trees in the imagery")
    weights, bias = train_linear_svm(np.vstack([positive, negative]),
                                     np.concatenate([np.ones(len(positive)), -np.ones(len(negative))]),
                                     c=COLOUR_SVM_C, seed=int(rng.randint(1 << 30)))
    return weights[None, :], bias


def _kmeans(points: np.ndarray, k: int, rng: np.random.RandomState, iterations: int = 25) -> np.ndarray:
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


def positive_windows(frames: Sequence[Frame], species: str, margin: float,
                     rng: np.random.RandomState) -> Iterator[tuple]:
    """(frame, cx, cy, side, transform) of the augmented positives: POSITIVE_COPIES per complete tree, all but
    the first with size and centre jitter, each in a random rotation/mirror (0..7)."""
    for frame in frames:
        for box in frame.trees(species):
            base = dataset.crown_size(box) * margin
            for copy in range(POSITIVE_COPIES):
                side = base * np.exp(rng.uniform(-np.log(SIZE_JITTER), np.log(SIZE_JITTER))) if copy else base
                dx, dy = np.clip(rng.normal(0, CENTRE_JITTER, 2), -2.5 * CENTRE_JITTER, 2.5 * CENTRE_JITTER) * side
                cx, cy = box.x_center + dx, box.y_center + dy
                if side >= features.HOG_WINDOW and frame.window_fits(cx, cy, side):
                    yield frame, cx, cy, side, rng.randint(8)


def positive_descriptors(frames: Sequence[Frame], species: str, margin: float,
                         rng: np.random.RandomState) -> np.ndarray:
    out = [dataset.top_descriptor(frame, cx, cy, side, transform=transform)
           for frame, cx, cy, side, transform in positive_windows(frames, species, margin, rng)]
    return np.array(out, np.float32).reshape(-1, features.hog_descriptor_length())


def crop_descriptors(crops: Sequence, rng: np.random.RandomState) -> tuple[np.ndarray, np.ndarray]:
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


def negative_descriptors(frames: Sequence[Frame], species: str, margin: float, rng: np.random.RandomState,
                         survey: bool = False) -> np.ndarray:
    out = []
    for frame in frames:
        for cx, cy, side in negative_windows(frame, species, margin, rng, survey):
            out.append(dataset.top_descriptor(frame, cx, cy, side, transform=rng.randint(8)))
    return np.array(out, np.float32).reshape(-1, features.hog_descriptor_length())


def negative_windows(frame: Frame, species: str, margin: float, rng: np.random.RandomState,
                     survey: bool = False) -> list[tuple[float, float, int]]:
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


def survey_windows(frame: Frame, margin: float) -> tuple[int, ...]:
    """Window sizes for mining a survey frame at its own crown scale: its crown sizes x margin, at most 3."""
    sizes = sorted({max(features.HOG_WINDOW, int(round(dataset.crown_size(b) * margin)))
                    for b in frame.boxes if b.label})
    if len(sizes) > 3:
        sizes = [sizes[len(sizes) // 10], sizes[len(sizes) // 2], sizes[(9 * len(sizes)) // 10]]
    return tuple(s for s in sizes if s <= min(frame.width, frame.height))


def hard_negatives(frames: Sequence[Frame], species: str, model: TreeModel, rng: np.random.RandomState,
                   survey: bool = False) -> np.ndarray:
    """Windows the current model scores above HARD_NEGATIVE_SCORE that are not trees of the species (survey
    imagery: at the frame's crown scale, inside its annotated area). Vectorised over each score map: a
    survey image holds hundreds of thousands of windows. Per frame and round: the best half of the quota and a
    random half of the rest (camera frames: HARD_NEGATIVES_PER_FRAME; survey frames: hard_negative_quota)."""
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
        quota = hard_negative_quota(frame, species) if survey else HARD_NEGATIVES_PER_FRAME
        if len(found) > quota:
            found.sort(key=lambda f: -f[0])
            keep = found[:quota // 2]
            rest = found[quota // 2:]
            picks = rng.choice(len(rest), quota - len(keep), replace=False)
            found = keep + [rest[i] for i in sorted(picks)]
        for _score, cx, cy, side in found:
            out.append(dataset.top_descriptor(frame, cx, cy, side))
    return np.array(out, np.float32).reshape(-1, features.hog_descriptor_length())


def hard_negative_quota(frame: Frame, species: str) -> int:
    """Hard negatives mined per round from one survey frame: one per complete crown of the species, at least
    HARD_NEGATIVES_PER_FRAME. A survey image of 60 crowns has the false alarms of many camera frames; ten per
    image (the camera frames' quota) left most of them unseen by the SVM."""
    return max(HARD_NEGATIVES_PER_FRAME, int(round(SURVEY_HARD_NEGATIVES_PER_CROWN * len(frame.trees(species)))))


def _area_mask(frame: Frame) -> np.ndarray:
    """Boolean image of the frame's annotated area (all False without labelled boxes)."""
    mask = np.zeros((frame.height, frame.width), np.uint8)
    area = frame.annotated_area()
    if area is not None:
        cv2.fillConvexPoly(mask, np.round(area.reshape(-1, 2)).astype(np.int32), 1)
    return mask.astype(bool)


# ---------------------------------------------------------------------------------------------------------
# The second stage (survey imagery): a finer HOG of the windows the first stage lets through


SECOND_STAGE_SCORE = -1.0  # first-stage group bests above this are the second stage's false alarms to learn
SECOND_STAGE_SPREAD = (0.85, 1.0, 1.18)  # false alarms at typical crown x margin x these (detection's sizes)


def second_descriptor(frame: Frame, cx: float, cy: float, side: float, window: int, kind: str = "hog",
                      transform: int = 0) -> np.ndarray:
    """foranav_features.second_stage_descriptor of a frame window; transform 0..7 as dataset.top_descriptor."""
    rows, cols = dataset.pixel_window(frame, cx, cy, side)
    crop = frame.value[rows, cols]
    if transform % 4:
        crop = np.rot90(crop, transform % 4)
    if transform >= 4:
        crop = crop[:, ::-1]
    return features.second_stage_descriptor(np.ascontiguousarray(crop), window, kind)


class Representatives:
    """first_stage_representatives of each frame for one model, computed once: the second stage and the network
    learn from the same windows, and on a survey photo of a hundred crowns finding them is most of the work."""

    def __init__(self, model: TreeModel):
        self.model = model
        self.found: dict[int, list[tuple]] = {}

    def __call__(self, frame: Frame) -> list[tuple]:
        if id(frame) not in self.found:
            self.found[id(frame)] = first_stage_representatives(frame, self.model)
        return self.found[id(frame)]


def second_stage_examples(frames: Sequence[Frame], species: str, model: TreeModel, window: int, kind: str,
                          rng: np.random.RandomState, survey: bool,
                          representatives: Representatives | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(descriptors, labels) of the second stage from one imagery's learning frames: the positives as the
    first stage's (augmented crowns), the first stage's negative windows and, on survey frames, the first
    stage's own false alarms: each group's best window above SECOND_STAGE_SCORE (colour and texture not
    applied) inside the annotated area that is not a tree window."""
    x, y = [], []
    margin = model.window_margin
    for frame in frames:
        for _frame, cx, cy, side, transform in positive_windows([frame], species, margin, rng):
            x.append(second_descriptor(frame, cx, cy, side, window, kind, transform))
            y.append(1)
        for cx, cy, side in negative_windows(frame, species, margin, rng, survey):
            x.append(second_descriptor(frame, cx, cy, side, window, kind, rng.randint(8)))
            y.append(-1)
        if survey:
            for _score, cx, cy, side in first_stage_false_alarms(frame, species, model, representatives):
                x.append(second_descriptor(frame, cx, cy, side, window, kind, rng.randint(8)))
                y.append(-1)
    return np.array(x, np.float32).reshape(-1, features.second_stage_length(window, kind)), np.array(y)


def first_stage_false_alarms(frame: Frame, species: str, model: TreeModel,
                             representatives: Representatives | None = None) -> list[tuple]:
    """[(score, cx, cy, side)]: the first stage's group-best windows on a survey frame at its crown scale, inside
    its annotated area, that are not tree windows."""
    found = representatives(frame) if representatives is not None else first_stage_representatives(frame, model)
    return [c for c in found if frame.in_area(c[1], c[2])
            and not dataset.is_tree_window(frame, species, c[1], c[2], c[3], model.window_margin, 0.25, 1.6)]


def first_stage_representatives(frame: Frame, model: TreeModel) -> list[tuple]:
    """[(score, cx, cy, side)]: the first stage's group-best windows (scoring above SECOND_STAGE_SCORE; colour
    and the later tests not applied) on a survey frame at its crown scale."""
    crown = frame.typical_crown()
    sizes = sorted(set(max(features.HOG_WINDOW, int(round(crown * model.window_margin * spread)))
                       for spread in SECOND_STAGE_SPREAD))
    sizes = tuple(s for s in sizes if s <= min(frame.width, frame.height))
    if not sizes:
        return []
    detector = detector_core.TreeDetector(model, detector_core.DetectorSettings(
        window_sizes=sizes, max_detections=None, svm_threshold=SECOND_STAGE_SCORE, hs_threshold=-2.0,
        variance_threshold=-1.0))
    trace = {}
    detector.detections_from_maps(detector.score_maps(frame.value), frame.hsv, frame.value, trace)
    return trace["nms"]

