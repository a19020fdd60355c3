# ForaNav tree detector: the pure core (frame in, detections out). Camera and host alike.
#
# Pipeline per frame (paper section III-A), cheapest test first:
#   1. HSV of the frame once (COLOR_BGR2HSV_FULL); the value channel feeds the top layer.
#   2. The top layer's linear SVM score of EVERY window of every size, from one atlas of the value channel
#      downscaled per window size: a dozen whole-image operations (foranav_score_maps).
#   3-4. Candidates (score-map peaks above svm_threshold) grouped into objects by non-maximum suppression
#      across window sizes; a window that is part of an accepted crown is the same tree (foranav_grouping).
#   5. Only each group's best window gets the per-window tests, cheapest first: the colour score of the
#      window's central region (the crown, not the ground around it) against the imagery's colour model
#      (rejects roofs, road crossings, other palms' colours), then the bottom layer's contrast-normalised
#      global HOG histogram on the full-resolution window (foranav_features.hog_texture: rejects other palm
#      species).
#      A model trained on survey imagery may add a second stage between the two: a linear SVM on a finer HOG
#      of the window and its radial cue (foranav_features.second_stage_descriptor), trained on the first
#      stage's false alarms.
#   6. A group that passes is one detection, centred on its members near the best one (foranav_grouping).
# Every threshold is a setting (DetectorSettings) whose default comes from the model file. A model holds one
# colour model and threshold set per imagery ("domain"); the detector uses the one named in the settings,
# else, for a model of several, the one whose training frames' colours are nearest the frame's.
import cv2
import numpy as np

import foranav_cnn
import foranav_colour as colours

import foranav_features as features
import foranav_grouping as grouping
import foranav_period as period
import foranav_score_maps as score_maps
from foranav_grouping import Detection, window_in_frame  # noqa: F401  (host tools cut windows with it)


DEFAULT_STEP = 2  # window step in downscaled pixels = W/12 (paper: 8 = W/3, see PAPER_STEP)
PAPER_STEP = features.HOG_WINDOW // 3
DEFAULT_NMS_OVERLAP = grouping.DEFAULT_NMS_OVERLAP
DEFAULT_MAX_DETECTIONS = 8  # the camera's maxtrees default; None = every tree (the host's detect)
DEFAULT_SMOOTHING = 1.0  # removes single-window noise peaks; a crown's blob of high scores is wider
MAX_CANDIDATES = 64  # per frame, best first: bounds the work when a frame is full of tree-like texture
CANDIDATES_PER_DETECTION = 8  # ... raised to this many per allowed detection
EDGE_TEST_OFF = float("-inf")  # edge_threshold that switches the edge test off
GROUPINGS = ("nms", "period")  # today's grouping (default), the period-tied peak stage (opt-in)
PERIOD_SUPPRESSION = 0.6  # the period stage's suppression radius, in planting periods
MIN_PERIOD_WINDOWS = 0.6  # a period estimated from the frame lies between this x the smallest window ...
MAX_PERIOD_WINDOWS = 2.0  # ... and this x the largest (outside: frond texture or no grid; today's grouping)


class DetectorSettings(object):
    """The detector's tunable settings. None = take the model's value.

    svm_threshold       top-layer linear SVM score a window must exceed (decision boundary = 0)
    variance_threshold  bottom-layer texture cue (foranav_features.hog_texture, 1/px^2) a detection must exceed
    hs_threshold        mean hue/saturation Pearson correlation with the template a detection must exceed
    second_threshold    second-stage score a detection's window must exceed (models with a second stage)
    cnn_threshold       the network's logit a detection's window must exceed (models with one, foranav_cnn)
    window_sizes        sliding-window sides W in pixels of THIS frame (None: the model's, scaled by
                        frame width / model reference width and rounded to a multiple of W_d = 24)
    step                window step in downscaled pixels (1..24; 2 = W/12 default, 8 = W/3 as in the paper)
    nms_overlap         IoU above which windows are merged into one object
    smoothing           Gaussian sigma applied to each score map before peaks are taken, in lattice units
                        (gcd(step, 6) downscaled pixels: W/12 by default); 0 = none
    max_detections      at most this many detections per frame, best first (None: no limit)
    domain              name of the model's imagery whose colour model and thresholds to use (None: the
                        only one, or the one nearest each frame's colours)
    grouping            "nms": today's grouping (overlap NMS; a window that is part of an accepted crown is
                        the same tree); "period": the period-tied peak stage, peaks suppressed within
                        PERIOD_SUPPRESSION planting periods of a stronger one, whatever the window size, so
                        that touching crowns (a period apart) stay apart (foranav_period)
    period_px           the period stage's planting period in frame pixels (e.g. the flight map's tree
                        spacing at the current height); None: estimated from each frame's autocorrelation,
                        and a frame without a clear one falls back to today's grouping
    edge_threshold      score a peak on the border of its score map (window touching the frame edge) must
                        also exceed (EDGE_TEST_OFF: no such test). Such a peak is not a verified maximum:
                        the score may keep rising outside the frame, where the rest of a cut crown is.
                        On the rendered oil-palm hold-out frames 16 of the 23 false detections were such
                        peaks of crowns cut by the edge, all scoring below 0; complete crowns near the
                        edge mostly score above 0.4. `foranav train` chooses it (best frame F1).
    """

    def __init__(self, svm_threshold=None, variance_threshold=None, hs_threshold=None, window_sizes=None,
                 step=DEFAULT_STEP, nms_overlap=DEFAULT_NMS_OVERLAP, max_detections=DEFAULT_MAX_DETECTIONS,
                 smoothing=DEFAULT_SMOOTHING, edge_threshold=None, domain=None, second_threshold=None,
                 cnn_threshold=None, grouping="nms", period_px=None):
        self.svm_threshold = svm_threshold
        self.variance_threshold = variance_threshold
        self.hs_threshold = hs_threshold
        self.second_threshold = second_threshold
        self.cnn_threshold = cnn_threshold
        self.window_sizes = tuple(window_sizes) if window_sizes else None
        self.step = int(step)
        self.nms_overlap = float(nms_overlap)
        self.max_detections = None if max_detections is None else int(max_detections)
        self.domain = domain
        self.smoothing = float(smoothing)
        self.grouping = grouping
        self.period_px = None if period_px is None else float(period_px)
        if self.grouping not in GROUPINGS:
            raise ValueError("grouping must be one of %s" % ", ".join(GROUPINGS))
        if self.period_px is not None and not 0.0 < self.period_px < float("inf"):
            raise ValueError("period_px must be a positive number of pixels")
        self.edge_threshold = None if edge_threshold is None else float(edge_threshold)
        if self.edge_threshold is not None and self.edge_threshold != self.edge_threshold:
            raise ValueError("edge_threshold must be a number")
        if not 1 <= self.step <= features.HOG_WINDOW:
            raise ValueError("step must be 1..%d downscaled pixels" % features.HOG_WINDOW)
        if not 0.0 < self.nms_overlap < 1.0:
            raise ValueError("nms_overlap must be between 0 and 1")
        if self.max_detections is not None and self.max_detections < 1:
            raise ValueError("max_detections must be at least 1")


def model_window_sizes(model, frame_width):
    """The model's window sizes for a frame of this width: scaled with the width (the lens' pixels per
    metre scale with it), rounded to a multiple of W_d so that downscaling is an exact block average."""
    factor = frame_width / float(model.reference_width)
    sizes = []
    for window in model.window_sizes:
        rounded = max(1, int(round(window * factor / features.HOG_WINDOW))) * features.HOG_WINDOW
        if rounded not in sizes:
            sizes.append(rounded)
    return tuple(sizes)


def crown_window_sizes(model, crown_px):
    """Window sides for a frame whose typical crown is crown_px pixels across: crown_px x the model's
    calibrated window/crown ratios (at least W_d)."""
    sizes = []
    for ratio in model.crown_ratios:
        window = max(features.HOG_WINDOW, int(round(crown_px * ratio)))
        if window not in sizes:
            sizes.append(window)
    return tuple(sizes)



class TreeDetector(object):
    """Detects trees of the model's species in BGR frames. Keeps per-frame-shape plans between calls."""

    def __init__(self, model, settings=None):
        self.model = model
        self.settings = settings or DetectorSettings()
        self._scorer = score_maps.WindowScorer(model.svm_weights, model.svm_bias)
        self._plans = {}
        self._window_scores = {}
        self._period = period.PeriodEstimator()
        self._cnn = None if model.cnn_onnx is None else foranav_cnn.CnnStage(model.cnn_onnx, model.cnn_side)
        self._colour = [colours.prepare_colour_vectors(model.colour_kind, d.colour_vectors) for d in model.domains]
        self._fixed_domain = None
        if self.settings.domain is not None:
            self._fixed_domain = [d.name for d in model.domains].index(model.domain(self.settings.domain).name)
        elif len(model.domains) == 1:
            self._fixed_domain = 0
        self.domain_index = self._fixed_domain or 0  # the domain of the last frame

    def select_domain(self, hsv):
        """Index of the domain for this frame: the fixed one, else the nearest by whole-frame colour."""
        if self._fixed_domain is not None:
            return self._fixed_domain
        colour = colours.frame_colour(hsv)
        similarities = [colours.frame_colour_similarity(colour, d.frame_colour) for d in self.model.domains]
        return int(np.argmax(similarities))

    # -- settings resolved against the model --------------------------------------------------------------

    def threshold(self, name):
        """A threshold: the setting, else the current domain's (the edge threshold is the model's)."""
        value = getattr(self.settings, name)
        if value is not None:
            return float(value)
        if name == "edge_threshold":
            return float(self.model.edge_threshold)
        return float(getattr(self.model.domains[self.domain_index], name))

    def thresholds(self):
        """(svm, hs, variance) thresholds of the current domain, settings first (see passes_thresholds)."""
        return (self.threshold("svm_threshold"), self.threshold("hs_threshold"),
                self.threshold("variance_threshold"))

    def window_sizes(self, frame_width):
        return self.settings.window_sizes or model_window_sizes(self.model, frame_width)

    def plans(self, frame_height, frame_width):
        return self._atlas(frame_height, frame_width).plans

    def _atlas(self, frame_height, frame_width):
        key = (frame_height, frame_width, self.window_sizes(frame_width), self.settings.step)
        if key not in self._plans:
            plans = [score_maps.ScalePlan(frame_height, frame_width, w, self.settings.step) for w in key[2]]
            if not any(p.usable for p in plans):
                raise ValueError("window sizes %s do not fit a %dx%d frame"
                                 % (", ".join("%g" % w for w in key[2]), frame_width, frame_height))
            self._plans = {key: score_maps.Atlas(plans)}  # one frame shape at a time: bounded memory
        return self._plans[key]

    # -- the pipeline -------------------------------------------------------------------------------------

    def detect(self, bgr, hsv=None):
        """Trees in one BGR frame -> list of Detection, best first (centre x, y, box w, h, SVM score)."""
        hsv = features.bgr_to_hsv(bgr) if hsv is None else hsv
        value = cv2.extractChannel(hsv, 2)
        maps = self.score_maps(value)
        return self.detections_from_maps(maps, hsv, value)

    def score_maps(self, value):
        """[(plan, score map)] of every window of every size, from the full-resolution value channel."""
        atlas = self._atlas(*value.shape)
        atlas.fill(value)
        self._window_scores = {}  # a new frame
        return atlas.split(self._scorer.scores(atlas))

    def detections_from_maps(self, maps, hsv, value, trace=None):
        """Steps 3-6: candidates, grouping, per-object tests, fused centres (shared with the reference).

        trace: a dict to receive each stage's survivors (host tools: the funnel), else None."""
        self.domain_index = self.select_domain(hsv)
        svm_threshold = self.threshold("svm_threshold")
        edge_threshold = self.threshold("edge_threshold")
        candidates = []
        for plan, scores in maps:
            if self.settings.smoothing > 0:  # the peak of a tree's blob of high scores, not of its noise
                scores = cv2.GaussianBlur(scores, (0, 0), self.settings.smoothing / plan.stride)
            candidates.extend(grouping.local_maxima(plan, scores, svm_threshold, edge_threshold))
        candidates.sort(key=lambda c: -c[0])
        if trace is not None:
            trace.update(maps=maps, peaks=list(candidates), nms=[], colour=[], cnn=[], second=[],
                         domain=self.domain_index)
        if self.settings.max_detections is not None:
            del candidates[max(MAX_CANDIDATES, CANDIDATES_PER_DETECTION * self.settings.max_detections):]
        radius = self.suppression_radius(value)
        if trace is not None:
            trace["capped"] = list(candidates)
            trace["suppression_radius"] = radius
        detections = []
        hs_threshold, variance_threshold = self.threshold("hs_threshold"), self.threshold("variance_threshold")
        margin = self.model.window_margin
        groups = (grouping.group(candidates, self.settings.nms_overlap) if radius is None
                  else grouping.group_by_centre(candidates, radius))
        for group in groups:
            group = self.representative_first(grouping.anchored(group), detections, hsv, hs_threshold, trace,
                                              radius)
            if group is None:
                continue
            x0, y0, side = window = grouping.pixel_window(group[0], value.shape)
            rows, cols = slice(y0, y0 + side), slice(x0, x0 + side)
            if self._cnn is not None and self._window_score("cnn", window, lambda: self._cnn.scores(
                    [hsv[rows, cols]])[0]) <= self.threshold("cnn_threshold"):
                continue
            if trace is not None:
                trace["cnn"].append(group[0])
            if self.model.second_window is not None and self._window_score("second", window, lambda: (
                    self.model.second_score(value[rows, cols]))) <= self.threshold("second_threshold"):
                continue
            if trace is not None:
                trace["second"].append(group[0])
            if self._window_score("texture", window, lambda: features.hog_texture(value[rows, cols])) \
                    > variance_threshold:
                detections.append(grouping.fuse(group, svm_threshold, margin))
                if len(detections) == self.settings.max_detections:
                    break
        return detections

    def suppression_radius(self, value):
        """The period stage's suppression radius in frame pixels, or None for today's grouping (the default,
        or a frame whose autocorrelation shows no clear period)."""
        if self.settings.grouping != "period":
            return None
        spacing = self.settings.period_px
        if spacing is None:
            sizes = self.window_sizes(value.shape[1])
            spacing = self._period.estimate(value, MIN_PERIOD_WINDOWS * min(sizes),
                                            MAX_PERIOD_WINDOWS * max(sizes))
        return None if spacing is None else PERIOD_SUPPRESSION * spacing

    def representative_first(self, group, detections, hsv, hs_threshold, trace, radius=None):
        """The group with its representative first, or None: the first window, of the group's anchor and then
        the smaller windows the anchor holds (best first), that is not part of an accepted crown and passes
        the colour test.

        A large window on a crown touching its neighbour can outscore the crown-sized windows inside it (the
        neighbour's edge fills their ring) while it spans the neighbour or the background beside the crown:
        it then fails the colour test, or shares more than COVER_FRACTION with the neighbour's accepted
        window, and used to take the crown-sized windows down with it. From straight above a 75-99 px crown
        touching a larger one at 1.3-1.5 m (sweep flights 43, 119, 294) the 144-168 px window failed colour
        (0.41-0.62) while the 96-120 px windows it held scored 0.95-0.99, and the crown went unseen for a
        minute; in flight 6 a 168 px window reaching 32 px towards the next tree was dropped as that tree's.
        radius: the period stage's suppression radius (a window centred that near an accepted detection is
        part of it), None for today's rule (grouping.inside_a_crown)."""
        anchor = group[0]
        margin = self.model.window_margin
        for window in [anchor] + [c for c in group[1:] if grouping.holds(anchor, c)]:
            if (grouping.inside_a_crown(window, detections, margin) if radius is None
                    else grouping.near_a_centre(window, detections, radius)):
                continue
            x0, y0, side = grouping.pixel_window(window, hsv.shape)
            if trace is not None and window is anchor:  # "nms": groups' best windows (funnel, hard negatives)
                trace["nms"].append(window)
            if self._window_score("colour", (x0, y0, side), lambda: self.colour_score(
                    hsv[y0:y0 + side, x0:x0 + side])) > hs_threshold:
                if trace is not None:
                    trace["colour"].append(window)
                return [window] + [c for c in group if c is not window]
        return None

    def _window_score(self, kind, window, compute):
        """A per-window score (colour, network, second stage, texture) of the frame of the last score_maps,
        computed once: host calibration runs the later steps many times on one frame's maps."""
        key = (kind, self.domain_index) + tuple(window)
        if key not in self._window_scores:
            self._window_scores[key] = compute()
        return self._window_scores[key]

    def colour_score(self, hsv_window):
        """The window's colour score against the current domain's colour model."""
        hue, sat = colours.smoothed_hs(hsv_window)
        domain = self.model.domains[self.domain_index]
        return colours.colour_score(self.model.colour_kind, self._colour[self.domain_index], domain.colour_bias,
                                     hue, sat)



def threshold_tests(score, colour, texture, svm_threshold, hs_threshold, variance_threshold):
    """The three-threshold rule, test by test: (SVM score, colour score, texture cue) each exceeds its
    threshold. Numbers, or numpy arrays (elementwise)."""
    return score > svm_threshold, colour > hs_threshold, texture > variance_threshold


def passes_thresholds(score, colour, texture, svm_threshold, hs_threshold, variance_threshold):
    """The three-threshold rule: a window is a tree when all three tests pass (elementwise for arrays)."""
    svm_ok, colour_ok, texture_ok = threshold_tests(score, colour, texture, svm_threshold, hs_threshold,
                                                    variance_threshold)
    if isinstance(svm_ok, np.ndarray):
        return svm_ok & colour_ok & texture_ok
    return svm_ok and colour_ok and texture_ok
