# ForaNav tree detector: the pure core (frame in, detections out). Camera and host alike.
#
# Pipeline per frame (paper section III-A), cheapest test first:
#   1. HSV of the frame once (COLOR_BGR2HSV_FULL); the value channel feeds the top layer.
#   2. For each window size W the value channel is downscaled once by W_d/W; the downscaled frames sit side
#      by side in one atlas image, whose gradients, orientation votes, cell histograms (on a lattice of
#      gcd(step, 6) downscaled pixels), block norms and linear SVM scores of EVERY window of every size are
#      a dozen whole-image operations (see _score_atlas). Nothing is computed or allocated per window.
#   3. Candidates: windows whose (lightly smoothed) score exceeds svm_threshold and is a local maximum of
#      its map, refined to sub-step precision by a parabola through the neighbouring scores.
#   4. Non-maximum suppression across window sizes: candidates are grouped greedily by overlap with the best
#      remaining one; each group is one object. A group whose best window is centred inside the crown box
#      of an already accepted detection is the same tree (a small window on one side of a big crown).
#   5. Only each group's best window gets the per-window tests, cheapest first: the colour score of the
#      window's central region (the crown, not the ground around it) against the imagery's colour model
#      (rejects roofs, road crossings, other palms' colours), then the bottom layer's contrast-normalised
#      global HOG histogram on the full-resolution window (foranav_features.hog_texture: rejects other palm
#      species).
#      A model trained on survey imagery may add a second stage between the two: a linear SVM on a finer HOG
#      of the window and its radial cue (foranav_features.second_stage_descriptor), trained on the first
#      stage's false alarms.
#   6. A group that passes is one detection; its centre is the score^2-weighted mean of the refined centres
#      of its members near the best one (a few pixels better than any single window on a lattice).
# Every threshold is a setting (DetectorSettings) whose default comes from the model file. A model holds one
# colour model and threshold set per imagery ("domain"); the detector uses the one named in the settings,
# else, for a model of several, the one whose training frames' colours are nearest the frame's.
import collections
import math

import cv2
import numpy as np

import foranav_features as features

Detection = collections.namedtuple("Detection", "x y w h score")  # centre and box in frame pixels

DEFAULT_STEP = 2  # window step in downscaled pixels = W/12 (paper: 8 = W/3, see PAPER_STEP)
PAPER_STEP = features.HOG_WINDOW // 3
DEFAULT_NMS_OVERLAP = 0.3  # intersection over union above which two windows are the same object
DEFAULT_MAX_DETECTIONS = 8  # the camera's maxtrees default; None = every tree (the host's detect)
DEFAULT_SMOOTHING = 1.0  # removes single-window noise peaks; a crown's blob of high scores is wider
FUSION_RADIUS = 0.15  # windows centred within this fraction of the best window's side are averaged
COVER_FRACTION = 0.5  # a window sharing more than this fraction of the smaller of two windows: one object
SCALE_TIE = 0.25  # SVM score within which a larger window holding the best one explains the crown better
MAX_CANDIDATES = 64  # per frame, best first: bounds the work when a frame is full of tree-like texture
CANDIDATES_PER_DETECTION = 8  # ... raised to this many per allowed detection
EDGE_TEST_OFF = float("-inf")  # edge_threshold that switches the edge test off


class DetectorSettings(object):
    """The detector's tunable settings. None = take the model's value.

    svm_threshold       top-layer linear SVM score a window must exceed (decision boundary = 0)
    variance_threshold  bottom-layer texture cue (foranav_features.hog_texture, 1/px^2) a detection must exceed
    hs_threshold        mean hue/saturation Pearson correlation with the template a detection must exceed
    second_threshold    second-stage score a detection's window must exceed (models with a second stage)
    window_sizes        sliding-window sides W in pixels of THIS frame (None: the model's, scaled by
                        frame width / model reference width and rounded to a multiple of W_d = 24)
    step                window step in downscaled pixels (1..24; 2 = W/12 default, 8 = W/3 as in the paper)
    nms_overlap         IoU above which windows are merged into one object
    smoothing           Gaussian sigma applied to each score map before peaks are taken, in lattice units
                        (gcd(step, 6) downscaled pixels: W/12 by default); 0 = none
    max_detections      at most this many detections per frame, best first (None: no limit)
    domain              name of the model's imagery whose colour model and thresholds to use (None: the
                        only one, or the one nearest each frame's colours)
    edge_threshold      score a peak on the border of its score map (window touching the frame edge) must
                        also exceed (EDGE_TEST_OFF: no such test). Such a peak is not a verified maximum:
                        the score may keep rising outside the frame, where the rest of a cut crown is.
                        On the rendered oil-palm hold-out frames 16 of the 23 false detections were such
                        peaks of crowns cut by the edge, all scoring below 0; complete crowns near the
                        edge mostly score above 0.4. `foranav train` chooses it (best frame F1).
    """

    def __init__(self, svm_threshold=None, variance_threshold=None, hs_threshold=None, window_sizes=None,
                 step=DEFAULT_STEP, nms_overlap=DEFAULT_NMS_OVERLAP, max_detections=DEFAULT_MAX_DETECTIONS,
                 smoothing=DEFAULT_SMOOTHING, edge_threshold=None, domain=None, second_threshold=None):
        self.svm_threshold = svm_threshold
        self.variance_threshold = variance_threshold
        self.hs_threshold = hs_threshold
        self.second_threshold = second_threshold
        self.window_sizes = tuple(window_sizes) if window_sizes else None
        self.step = int(step)
        self.nms_overlap = float(nms_overlap)
        self.max_detections = None if max_detections is None else int(max_detections)
        self.domain = domain
        self.smoothing = float(smoothing)
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


class _ScalePlan(object):
    """Everything about one window size that depends only on the frame shape: computed once, reused."""

    def __init__(self, frame_height, frame_width, window, step):
        self.window = float(window)
        self.scale = features.HOG_WINDOW / self.window
        factor = int(round(self.window)) // features.HOG_WINDOW
        if factor * features.HOG_WINDOW == self.window:
            # Integer factor: crop to whole blocks so that every downscaled pixel is an exact block mean
            # (cv2's INTER_AREA fast path) and any window equals its own crop, downscaled.
            self.crop_height = frame_height // factor * factor
            self.crop_width = frame_width // factor * factor
        else:
            self.crop_height, self.crop_width = frame_height, frame_width
        probe = cv2.resize(np.zeros((self.crop_height, self.crop_width), np.uint8), None, fx=self.scale,
                           fy=self.scale, interpolation=cv2.INTER_AREA)
        self.small_height, self.small_width = probe.shape
        self.lattice = math.gcd(step, features.HOG_CELL)  # cell histograms are computed every `lattice` px
        self.stride = step // self.lattice  # window step in lattice units
        cell = features.HOG_CELL // self.lattice  # one cell in lattice units
        cells_per_window = features.HOG_WINDOW // features.HOG_CELL
        self.map_height = self.small_height // self.lattice - cells_per_window * cell + 1
        self.map_width = self.small_width // self.lattice - cells_per_window * cell + 1
        self.usable = self.map_height > 0 and self.map_width > 0
        self.atlas_row = self.atlas_col = 0  # where the downscaled frame sits in the atlas (set by _Atlas)

    def window_origin(self, row, col):
        """Frame-pixel origin (x0, y0) of the window at (row, col) of this size's score map."""
        unit = self.stride * self.lattice / self.scale
        return col * unit, row * unit


class _Atlas(object):
    """One image holding every window size's downscaled frame side by side, each with a one-pixel
    replicated border, so that gradients, orientation binning, cell histograms, block norms and scores are
    computed once per frame for all sizes (a dozen whole-image operations instead of a dozen per size).
    Each downscaled frame starts on the lattice, so its windows are a plain slice of the atlas' score map."""

    def __init__(self, plans):
        self.plans = [p for p in plans if p.usable]
        g = self.plans[0].lattice
        col = 0
        for plan in self.plans:
            plan.atlas_row = g  # room for the border row above, on the lattice
            plan.atlas_col = _round_up(col + 1, g)
            col = plan.atlas_col + plan.small_width + 1
        height = _round_up(g + max(p.small_height for p in self.plans) + 1, g)
        width = _round_up(col, g)
        self.image = np.zeros((height, width), np.uint8)
        self.lattice = g
        self.cell = features.HOG_CELL // g
        # Work buffers, reused every frame (fresh megabyte-sized arrays would cost page faults each frame).
        # Per-bin data is planar, one (height, width) image per bin: single-channel look-ups, products and
        # block means are several times faster than on a 9-channel interleaved image.
        bins = features.HOG_BINS
        self.weights = np.empty((bins, height, width), np.uint8)
        self.votes = np.empty((bins, height, width), np.uint16)
        self.lattice_votes = np.empty((bins * height // g, width // g), np.uint16)

    def fill(self, value):
        for plan in self.plans:
            small = cv2.resize(value[:plan.crop_height, :plan.crop_width], None, fx=plan.scale, fy=plan.scale,
                               interpolation=cv2.INTER_AREA)
            self.image[plan.atlas_row - 1:plan.atlas_row + plan.small_height + 1,
                       plan.atlas_col - 1:plan.atlas_col + plan.small_width + 1] = cv2.copyMakeBorder(
                small, 1, 1, 1, 1, cv2.BORDER_REPLICATE)
        return self.image

    def split(self, scores):
        """[(plan, score map)] from the atlas' score map."""
        g = self.lattice
        out = []
        for plan in self.plans:
            row, col = plan.atlas_row // g, plan.atlas_col // g
            region = scores[row:row + plan.map_height:plan.stride, col:col + plan.map_width:plan.stride]
            out.append((plan, np.ascontiguousarray(region)))
        return out


class TreeDetector(object):
    """Detects trees of the model's species in BGR frames. Keeps per-frame-shape plans between calls."""

    def __init__(self, model, settings=None):
        self.model = model
        self.settings = settings or DetectorSettings()
        # The SVM weights regrouped as (bin, block row, block col, cell row, cell col) for _score_atlas.
        blocks = (features.HOG_WINDOW // features.HOG_CELL - features.HOG_BLOCK) // features.HOG_BLOCK_STRIDE + 1
        self._blocks = blocks
        weights = model.svm_weights.reshape(blocks, blocks, features.HOG_BLOCK, features.HOG_BLOCK,
                                            features.HOG_BINS)
        self._cell_weights = np.ascontiguousarray(
            weights.transpose(4, 0, 1, 2, 3).reshape(features.HOG_BINS, -1)).astype(np.float32)
        self._bin_tables = [np.ascontiguousarray(features.SOFT_BIN_TABLE_U8[:, b]) for b in range(features.HOG_BINS)]
        self._plans = {}
        self._second_scores = {}
        self._colour = [features.prepare_colour_vectors(model.colour_kind, d.colour_vectors) for d in model.domains]
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
        colour = features.frame_colour(hsv)
        similarities = [features.frame_colour_similarity(colour, d.frame_colour) for d in self.model.domains]
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
            plans = [_ScalePlan(frame_height, frame_width, w, self.settings.step) for w in key[2]]
            if not any(p.usable for p in plans):
                raise ValueError("window sizes %s do not fit a %dx%d frame"
                                 % (", ".join("%g" % w for w in key[2]), frame_width, frame_height))
            self._plans = {key: _Atlas(plans)}  # one frame shape at a time: bounded memory
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
        self._second_scores = {}  # a new frame
        return atlas.split(self._score_atlas(atlas))

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
            candidates.extend(_local_maxima(plan, scores, svm_threshold, edge_threshold))
        candidates.sort(key=lambda c: -c[0])
        if trace is not None:
            trace.update(maps=maps, peaks=list(candidates), nms=[], colour=[], second=[], domain=self.domain_index)
        if self.settings.max_detections is not None:
            del candidates[max(MAX_CANDIDATES, CANDIDATES_PER_DETECTION * self.settings.max_detections):]
        if trace is not None:
            trace["capped"] = list(candidates)
        detections = []
        hs_threshold, variance_threshold = self.threshold("hs_threshold"), self.threshold("variance_threshold")
        margin = self.model.window_margin
        for group in _group(candidates, self.settings.nms_overlap):
            group = self._representative_first(_anchored(group), detections, hsv, hs_threshold, trace)
            if group is None:
                continue
            x0, y0, side = _pixel_window(group[0], value.shape)
            if self.model.second_window is not None and self.second_score(
                    value[y0:y0 + side, x0:x0 + side], (x0, y0, side)) <= self.threshold("second_threshold"):
                continue
            if trace is not None:
                trace["second"].append(group[0])
            if features.hog_texture(value[y0:y0 + side, x0:x0 + side]) > variance_threshold:
                detections.append(_fuse(group, svm_threshold, margin))
                if len(detections) == self.settings.max_detections:
                    break
        return detections

    def _representative_first(self, group, detections, hsv, hs_threshold, trace):
        """The group with its representative first, or None: the first window, of the group's anchor and then
        the smaller windows the anchor holds (best first), that is not part of an accepted crown and passes
        the colour test.

        A large window on a crown touching its neighbour can outscore the crown-sized windows inside it (the
        neighbour's edge fills their ring) while it spans the neighbour or the background beside the crown:
        it then fails the colour test, or shares more than COVER_FRACTION with the neighbour's accepted
        window, and used to take the crown-sized windows down with it. From straight above a 75-99 px crown
        touching a larger one at 1.3-1.5 m (sweep flights 43, 119, 294) the 144-168 px window failed colour
        (0.41-0.62) while the 96-120 px windows it held scored 0.95-0.99, and the crown went unseen for a
        minute; in flight 6 a 168 px window reaching 32 px towards the next tree was dropped as that tree's."""
        anchor = group[0]
        margin = self.model.window_margin
        for window in [anchor] + [c for c in group[1:] if _holds(anchor, c)]:
            if _inside_a_crown(window, detections, margin):
                continue
            x0, y0, side = _pixel_window(window, hsv.shape)
            if trace is not None and window is anchor:  # "nms": groups' best windows (funnel, hard negatives)
                trace["nms"].append(window)
            if self.colour_score(hsv[y0:y0 + side, x0:x0 + side]) > hs_threshold:
                if trace is not None:
                    trace["colour"].append(window)
                return [window] + [c for c in group if c is not window]
        return None

    def second_score(self, value_window, key=None):
        """The second stage's score of a full-resolution value window (models with a second stage); key: the
        window's (x0, y0, side) in the frame of the last score_maps, whose scores are kept (host calibration
        runs the later steps many times on one frame's maps)."""
        if key is not None and key in self._second_scores:
            return self._second_scores[key]
        score = self.model.second_score(value_window)
        if key is not None:
            self._second_scores[key] = score
        return score

    def colour_score(self, hsv_window):
        """The window's colour score against the current domain's colour model."""
        hue, sat = features.smoothed_hs(hsv_window)
        domain = self.model.domains[self.domain_index]
        return features.colour_score(self.model.colour_kind, self._colour[self.domain_index], domain.colour_bias,
                                     hue, sat)

    def _score_atlas(self, atlas):
        """Linear SVM score of the window at every lattice position of the atlas (g px apart; o = lattice
        units per cell).

        With cell histograms H on the lattice, block norms N and the weights w regrouped per (block, cell):
            score(p) = bias + sum_blocks [ sum_cells w_{block,cell} . H(p + block + cell) ] / N(p + block)
        computed as a few whole-image operations.
        """
        g, o, bins, k, n = atlas.lattice, atlas.cell, features.HOG_BINS, features.HOG_BLOCK, self._blocks
        codes, levels = features.gradient_levels(atlas.image)
        for b in range(bins):  # each pixel's vote for bin b: magnitude code x soft-binning weight (uint16)
            cv2.LUT(levels, self._bin_tables[b], dst=atlas.weights[b])
            cv2.multiply(atlas.weights[b], codes, dst=atlas.votes[b], dtype=cv2.CV_16U)
        height, width = atlas.image.shape
        if g > 1:  # mean votes over g x g pixels (exact block mean): the lattice the cells are added from
            votes = cv2.resize(atlas.votes.reshape(bins * height, width), (width // g, bins * height // g),
                               dst=atlas.lattice_votes, interpolation=cv2.INTER_AREA)
            votes = votes.reshape(bins, height // g, width // g)
        else:
            votes = atlas.votes
        planes = votes.astype(np.float32)
        planes *= g * g * features.VOTE_UNIT
        cells = _box_sum(planes, o)  # cell histograms at every lattice position: (bins, rows, cols)
        # Block norms: sum of squared cell histograms over k x k cells, one map.
        energy = _box_sum(np.einsum("bij,bij->ij", cells, cells), o, k, step=o)
        inverse_norm = 1.0 / np.sqrt(energy + features.BLOCK_NORM_EPS ** 2)
        # Per (block, cell) responses w . H as maps (block row, block col, cell row, cell col, rows, cols),
        # then summed over the cells of each block.
        rows, cols = cells.shape[1], cells.shape[2]
        responses = self._cell_weights.T.dot(cells.reshape(bins, -1)).reshape(n, n, k, k, rows, cols)
        width = cols - (k - 1) * o
        row_sum = responses[:, :, :, 0, :, 0:width].copy()
        for c in range(1, k):
            row_sum += responses[:, :, :, c, :, c * o:c * o + width]
        height = rows - (k - 1) * o
        block_sum = row_sum[:, :, 0, 0:height, :].copy()
        for r in range(1, k):
            block_sum += row_sum[:, :, r, r * o:r * o + height, :]
        # Window score: blocks at offsets (by, bx) x block stride.
        bs = features.HOG_BLOCK_STRIDE * o
        map_height = height - (n - 1) * bs
        map_width = width - (n - 1) * bs
        scores = np.full((map_height, map_width), self.model.svm_bias, np.float32)
        for by in range(n):
            for bx in range(n):
                rows = slice(by * bs, by * bs + map_height)
                cols = slice(bx * bs, bx * bs + map_width)
                scores += block_sum[by, bx, rows, cols] * inverse_norm[rows, cols]
        return scores


def _round_up(value, multiple):
    return -(-value // multiple) * multiple


def _box_sum(array, size, count=None, step=1):
    """Sums over the last two axes of `count` entries spaced `step` apart (default: `size` consecutive)."""
    if count is None:
        count, step = size, 1
    span = (count - 1) * step
    height = array.shape[-2] - span
    width = array.shape[-1] - span
    rows = array[..., 0:height, :].copy()
    for i in range(1, count):
        rows += array[..., i * step:i * step + height, :]
    out = rows[..., 0:width].copy()
    for j in range(1, count):
        out += rows[..., j * step:j * step + width]
    return out


def _local_maxima(plan, scores, threshold, edge_threshold=None):
    """Candidates (score, centre x, centre y, window) at local maxima of one score map above threshold
    (and above edge_threshold too on the map's border)."""
    if not (scores > threshold).any():
        return []
    peaks = (scores > threshold) & (scores >= cv2.dilate(scores, np.ones((3, 3), np.uint8)))
    rows, cols = np.nonzero(peaks)
    last_row, last_col = scores.shape[0] - 1, scores.shape[1] - 1
    out = []
    for row, col in zip(rows.tolist(), cols.tolist()):
        if (edge_threshold is not None and scores[row, col] <= edge_threshold
                and (row == 0 or col == 0 or row == last_row or col == last_col)):
            continue
        dy = _parabola_offset(scores, row, col, 1, 0)
        dx = _parabola_offset(scores, row, col, 0, 1)
        x0, y0 = plan.window_origin(row + dy, col + dx)
        out.append((float(scores[row, col]), x0 + plan.window / 2.0, y0 + plan.window / 2.0, plan.window))
    return out


def _parabola_offset(scores, row, col, drow, dcol):
    """Sub-step position of a peak from the parabola through it and its two neighbours (-0.5..0.5)."""
    r0, c0, r1, c1 = row - drow, col - dcol, row + drow, col + dcol
    if r0 < 0 or c0 < 0 or r1 >= scores.shape[0] or c1 >= scores.shape[1]:
        return 0.0
    before, here, after = float(scores[r0, c0]), float(scores[row, col]), float(scores[r1, c1])
    curvature = before - 2.0 * here + after
    if curvature >= 0:
        return 0.0
    return max(-0.5, min(0.5, 0.5 * (before - after) / curvature))


def _iou(a, b):
    """Intersection over union of two square windows given as (score, cx, cy, side)."""
    inter = _shared(a, b)
    return inter / (a[3] * a[3] + b[3] * b[3] - inter)


def _group(candidates, overlap):
    """Greedy NMS on candidates sorted best first: each group = the best remaining + those overlapping it."""
    remaining = list(candidates)
    while remaining:
        best = remaining[0]
        group = [c for c in remaining if c is best or _iou(best, c) > overlap]
        remaining = [c for c in remaining if not (c is best or _iou(best, c) > overlap)]
        yield group


def _inside_a_crown(candidate, detections, margin):
    """True when the candidate is part of an accepted (stronger) detection's crown: its centre lies in that
    crown's box, or its window shares more than COVER_FRACTION of the smaller window with that detection's.

    IoU alone lets a small window on one side of a large crown survive (a 96 px window 45 px off the centre
    of a 168 px one: IoU 0.29): in the clustered rows of map 3 that gave a second detection on one tree in
    a quarter of the frames around it. It also lets a large window straddle a detected crown and the gap
    beside it (a 168 px window over half of a 120 px one: IoU 0.28, sweep flight 468 at 1.46 m) and report
    a tree between two trees. Two neighbouring crowns stand at least a crown apart: their windows (about
    1.3 crowns) share at most 0.4 of the smaller one, even one size step apart, so real neighbours are kept.
    Not when the accepted window is about 2 crowns (the largest size on a small crown, or an anchor): a
    96 px window on a touching neighbour one crown away then shares 0.54 and is dropped (arithmetic, not seen
    to cause a sweep failure). A dropped anchor does not take its group with it: the smaller windows it holds
    are tried next (TreeDetector._representative_first).
    """
    for d in detections:
        if abs(candidate[1] - d.x) < 0.5 * d.w and abs(candidate[2] - d.y) < 0.5 * d.h:
            return True
        side = d.w * margin
        if _shared(candidate, (d.score, d.x, d.y, side)) > COVER_FRACTION * min(candidate[3], side) ** 2:
            return True
    return False


def _shared(a, b):
    """Area shared by two square windows given as (score, cx, cy, side)."""
    ha, hb = a[3] / 2.0, b[3] / 2.0
    dx = min(a[1] + ha, b[1] + hb) - max(a[1] - ha, b[1] - hb)
    dy = min(a[2] + ha, b[2] + hb) - max(a[2] - ha, b[2] - hb)
    return dx * dy if dx > 0 and dy > 0 else 0.0


def _contains(outer, inner):
    """True when square window ``inner`` lies wholly inside ``outer`` (both (score, cx, cy, side))."""
    reach = (outer[3] - inner[3]) / 2.0
    return abs(outer[1] - inner[1]) <= reach and abs(outer[2] - inner[2]) <= reach


def _holds(outer, inner):
    """True when ``inner`` is a smaller window lying wholly inside ``outer``."""
    return inner[3] < outer[3] and _contains(outer, inner)


def _anchored(group):
    """The group with its anchor first: the largest window that holds the best one and scores within
    SCALE_TIE of it. A window well inside a large crown can outscore the crown-sized windows (fronds look
    like a small crown): from straight above a 0.45 m crown at 1.1 m the best window sat 30 px off centre,
    and the servo chased it for a minute. The crown-sized window holding it is centred on the crown."""
    best = group[0]
    anchor = best
    for c in group[1:]:
        if c[3] > anchor[3] and c[0] >= best[0] - SCALE_TIE and _contains(c, best):
            anchor = c
    if anchor is best:
        return group
    return [anchor] + [c for c in group if c is not anchor]


def _fuse(group, threshold, margin):
    """One Detection from a group: the best window's score; centre and size are the mean of the windows
    centred within FUSION_RADIUS of the best one, weighted by (score - threshold)^2 so that strong, well
    placed windows dominate and the off-centre side peaks of neighbouring sizes do not pull the centre."""
    best = group[0]
    radius = FUSION_RADIUS * best[3]
    group = [c for c in group if (c[1] - best[1]) ** 2 + (c[2] - best[2]) ** 2 <= radius * radius]
    weights = [max(c[0] - threshold, 1e-6) ** 2 for c in group]
    total = sum(weights)
    cx = sum(w * c[1] for w, c in zip(weights, group)) / total
    cy = sum(w * c[2] for w, c in zip(weights, group)) / total
    side = sum(w * c[3] for w, c in zip(weights, group)) / total / margin
    return Detection(cx, cy, side, side, group[0][0])


def window_in_frame(cx, cy, side, height, width):
    """Integer (x0, y0, side) of the square window of centre (cx, cy), kept inside a height x width frame
    (the window clamp; host tools cut their training and evaluation windows with it too)."""
    side = int(round(side))
    x0 = int(round(cx - side / 2.0))
    y0 = int(round(cy - side / 2.0))
    x0 = max(0, min(width - side, x0))
    y0 = max(0, min(height - side, y0))
    return x0, y0, side


def _pixel_window(candidate, shape):
    """Integer (x0, y0, side) of a candidate's window, kept inside the frame."""
    return window_in_frame(candidate[1], candidate[2], candidate[3], shape[0], shape[1])


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
