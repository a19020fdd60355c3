# ForaNav tree detector: from score-map peaks to one detection per tree. Camera and host alike.
#
# Candidates are the windows whose (smoothed) score is a local maximum of its map above the threshold,
# refined to sub-step precision by a parabola. Non-maximum suppression across window sizes groups them
# greedily by overlap with the best remaining one; each group is one object, represented by its anchor (the
# largest window that holds the best one and scores about as well). A window that is part of an accepted
# crown is the same tree. A group that passes the per-window tests (foranav_detector) becomes one Detection,
# centred on the score^2-weighted mean of its members near the anchor. Candidates are tuples
# (score, centre x, centre y, side) in frame pixels.
import collections

import cv2
import numpy as np

Detection = collections.namedtuple("Detection", "x y w h score")  # centre and box in frame pixels

DEFAULT_NMS_OVERLAP = 0.3  # intersection over union above which two windows are the same object
FUSION_RADIUS = 0.15  # windows centred within this fraction of the best window's side are averaged
COVER_FRACTION = 0.5  # a window sharing more than this fraction of the smaller of two windows: one object
SCALE_TIE = 0.25  # SVM score within which a larger window holding the best one explains the crown better


def local_maxima(plan, scores, threshold, edge_threshold=None):
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
        dy = parabola_offset(scores, row, col, 1, 0)
        dx = parabola_offset(scores, row, col, 0, 1)
        x0, y0 = plan.window_origin(row + dy, col + dx)
        out.append((float(scores[row, col]), x0 + plan.window / 2.0, y0 + plan.window / 2.0, plan.window))
    return out


def parabola_offset(scores, row, col, drow, dcol):
    """Sub-step position of a peak from the parabola through it and its two neighbours (-0.5..0.5)."""
    r0, c0, r1, c1 = row - drow, col - dcol, row + drow, col + dcol
    if r0 < 0 or c0 < 0 or r1 >= scores.shape[0] or c1 >= scores.shape[1]:
        return 0.0
    before, here, after = float(scores[r0, c0]), float(scores[row, col]), float(scores[r1, c1])
    curvature = before - 2.0 * here + after
    if curvature >= 0:
        return 0.0
    return max(-0.5, min(0.5, 0.5 * (before - after) / curvature))


def iou(a, b):
    """Intersection over union of two square windows given as (score, cx, cy, side)."""
    inter = shared(a, b)
    return inter / (a[3] * a[3] + b[3] * b[3] - inter)


def group(candidates, overlap):
    """Greedy NMS on candidates sorted best first: each group = the best remaining + those overlapping it.
    The overlaps of the best with all remaining are one array operation (a survey image has hundreds of
    candidates), with the very arithmetic of iou, so the groups are the same."""
    if not candidates:
        return
    boxes = np.array([c[1:4] for c in candidates], np.float64)  # cx, cy, side
    remaining = np.arange(len(candidates))
    while len(remaining):
        member = _ious(boxes[remaining[0]], boxes[remaining]) > overlap
        member[0] = True
        yield [candidates[i] for i in remaining[member].tolist()]
        remaining = remaining[~member]


def group_by_centre(candidates, radius):
    """The period stage's suppression, on candidates sorted best first: each group = the best remaining + those
    centred within radius of it, whatever their window size (radius from the planting period, not the
    crown size: two touching crowns stand a period apart, a crown's off-centre peaks well within it)."""
    if not candidates:
        return
    centres = np.array([c[1:3] for c in candidates], np.float64)
    remaining = np.arange(len(candidates))
    while len(remaining):
        offsets = centres[remaining] - centres[remaining[0]]
        member = (offsets * offsets).sum(axis=1) <= radius * radius
        member[0] = True
        yield [candidates[i] for i in remaining[member].tolist()]
        remaining = remaining[~member]


def near_a_centre(candidate, detections, radius):
    """The period stage's counterpart of inside_a_crown: the candidate is centred within radius of an
    accepted detection."""
    return any((candidate[1] - d.x) ** 2 + (candidate[2] - d.y) ** 2 <= radius * radius for d in detections)


def _ious(box, boxes):
    """iou of one window (cx, cy, side) with an array of them, elementwise."""
    half, halves = box[2] / 2.0, boxes[:, 2] / 2.0
    dx = np.minimum(box[0] + half, boxes[:, 0] + halves) - np.maximum(box[0] - half, boxes[:, 0] - halves)
    dy = np.minimum(box[1] + half, boxes[:, 1] + halves) - np.maximum(box[1] - half, boxes[:, 1] - halves)
    inter = np.where((dx > 0) & (dy > 0), dx * dy, 0.0)
    return inter / (box[2] * box[2] + boxes[:, 2] * boxes[:, 2] - inter)


def inside_a_crown(candidate, detections, margin):
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
    are tried next (foranav_detector.TreeDetector.representative_first).
    """
    for d in detections:
        if abs(candidate[1] - d.x) < 0.5 * d.w and abs(candidate[2] - d.y) < 0.5 * d.h:
            return True
        side = d.w * margin
        if shared(candidate, (d.score, d.x, d.y, side)) > COVER_FRACTION * min(candidate[3], side) ** 2:
            return True
    return False


def shared(a, b):
    """Area shared by two square windows given as (score, cx, cy, side)."""
    ha, hb = a[3] / 2.0, b[3] / 2.0
    dx = min(a[1] + ha, b[1] + hb) - max(a[1] - ha, b[1] - hb)
    dy = min(a[2] + ha, b[2] + hb) - max(a[2] - ha, b[2] - hb)
    return dx * dy if dx > 0 and dy > 0 else 0.0


def contains(outer, inner):
    """True when square window ``inner`` lies wholly inside ``outer`` (both (score, cx, cy, side))."""
    reach = (outer[3] - inner[3]) / 2.0
    return abs(outer[1] - inner[1]) <= reach and abs(outer[2] - inner[2]) <= reach


def holds(outer, inner):
    """True when ``inner`` is a smaller window lying wholly inside ``outer``."""
    return inner[3] < outer[3] and contains(outer, inner)


def anchored(group):
    """The group with its anchor first: the largest window that holds the best one and scores within
    SCALE_TIE of it. A window well inside a large crown can outscore the crown-sized windows (fronds look
    like a small crown): from straight above a 0.45 m crown at 1.1 m the best window sat 30 px off centre,
    and the servo chased it for a minute. The crown-sized window holding it is centred on the crown."""
    best = group[0]
    anchor = best
    for c in group[1:]:
        if c[3] > anchor[3] and c[0] >= best[0] - SCALE_TIE and contains(c, best):
            anchor = c
    if anchor is best:
        return group
    return [anchor] + [c for c in group if c is not anchor]


def fuse(group, threshold, margin):
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


def pixel_window(candidate, shape):
    """Integer (x0, y0, side) of a candidate's window, kept inside the frame."""
    return window_in_frame(candidate[1], candidate[2], candidate[3], shape[0], shape[1])

