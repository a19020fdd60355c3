"""Planting rows fitted through annotated crown centres (a pure core: points in, rows out).

Real plantings are not the generator's straight columns: palms are missing, rows bend, the block lies at any
heading and oil palms are planted in triangles, so three directions line palms up. The fit:

1. **Heading.** Every direction from 0 to 180 degrees (``HEADING_STEP_DEG``, then refined) is scored by how
   tightly the centres bunch when projected across it: the sum over pairs of a Gaussian of their across-row
   distance (``BUNCH_SIGMA_CROWN`` crowns). Along the true rows whole rows fall on one offset, so the direction
   with the best support wins (of a triangular planting's three, the one its palms line up best along); a
   given ``heading_deg`` skips the search.
2. **Rows.** Palms are taken in order along the heading; each joins the row whose continuation is nearest across
   (within ``JOIN_ACROSS_SPACING`` row spacings, the spacing being the median gap between the peaks of the
   across-row density) and not farther behind than ``MAX_GAP_PALMS`` palm spacings (missing palms), else it
   starts a row. "Nearest across" is measured from where the row's last palms point (a bend goes on
   bending), so rows may bend.
3. **Lines.** A row of at least ``MIN_ROW_PALMS`` palms becomes a least-squares line from its first to its
   last palm, or, where the palms leave that line by more than ``BEND_TOLERANCE_CROWN`` crowns, a polyline
   through the palms where it bends (Douglas-Peucker).

Row spacing: the median across-row distance between neighbouring rows (centre to centre).
"""
import math
from dataclasses import dataclass

import numpy as np

Point = tuple[float, float]
HEADING_STEP_DEG = 0.5
HEADING_REFINE_STEP_DEG = 0.05
BUNCH_SIGMA_CROWN = 0.15  # across-row spread of one row's centres the heading score tolerates (crowns)
JOIN_ACROSS_SPACING = 0.4  # a palm joins a row whose last palm is within this many row spacings across
MAX_GAP_PALMS = 3.2  # ... and at most this many palm spacings behind (two missing palms in a row)
MIN_ROW_PALMS = 3
MAX_PREDICTED_SLOPE = math.tan(math.radians(10.0))  # a row's local direction, against the heading
SLOPE_PALMS = 4  # a row's local direction: the line of its last this many palms
BEND_TOLERANCE_CROWN = 0.3  # a row bends where its palms leave the straight line by more than this


@dataclass(frozen=True)
class Row:
    members: tuple[int, ...]  # indices of the input points, in order along the heading
    line: tuple[Point, ...]  # first to last point of the fitted line (two) or bent polyline (more)
    offset: float  # mean across-row position (for ordering rows)


@dataclass(frozen=True)
class RowFit:
    heading_deg: float  # direction of the rows, counter-clockwise from +x, in [0, 180)
    row_spacing: float | None  # centre-to-centre distance between adjacent rows (None with a single row)
    palm_spacing: float  # median nearest-neighbour distance of the centres
    rows: tuple[Row, ...]  # ordered across the heading


def fit_rows(points: np.ndarray, crown: float, heading_deg: float | None = None) -> RowFit:
    """Rows through ``points`` (N x 2, same unit as ``crown``, the typical crown size); see the module doc."""
    points = np.asarray(points, float).reshape(-1, 2)
    palm_spacing = _palm_spacing(points, crown)
    if heading_deg is None:
        heading_deg = best_heading(points, crown)
    heading_deg = float(heading_deg) % 180.0
    along, across = _project(points, heading_deg)
    spacing = _row_spacing_from_density(across, crown)
    tolerance = JOIN_ACROSS_SPACING * (spacing if spacing is not None else palm_spacing)
    groups = _chain(along, across, tolerance, MAX_GAP_PALMS * palm_spacing)
    rows = []
    for members in groups:
        if len(members) < MIN_ROW_PALMS:
            continue
        line = _row_line(points[members], along[members], heading_deg, BEND_TOLERANCE_CROWN * crown)
        rows.append(Row(tuple(int(i) for i in members), line, float(np.mean(across[members]))))
    rows.sort(key=lambda r: (r.offset, along[r.members[0]]))
    return RowFit(heading_deg, _neighbour_spacing(rows, along, across, palm_spacing), palm_spacing, tuple(rows))


def best_heading(points: np.ndarray, crown: float) -> float:
    """The row direction (degrees in [0, 180)) along which the centres bunch best across."""
    coarse = np.arange(0.0, 180.0, HEADING_STEP_DEG)
    best = coarse[int(np.argmax([heading_support(points, h, crown) for h in coarse]))]
    fine = best + np.arange(-HEADING_STEP_DEG, HEADING_STEP_DEG + 1e-9, HEADING_REFINE_STEP_DEG)
    best = fine[int(np.argmax([heading_support(points, h, crown) for h in fine]))]
    return float(round(best % 180.0, 4))


def heading_support(points: np.ndarray, heading_deg: float, crown: float) -> float:
    """Sum over pairs of exp(-d^2 / 2 sigma^2), d their across-row distance: how well rows line up."""
    _, across = _project(points, heading_deg)
    d = across[:, None] - across[None, :]
    sigma = BUNCH_SIGMA_CROWN * crown
    return float((np.exp(-d * d / (2 * sigma * sigma)).sum() - len(across)) / 2)


def _project(points, heading_deg):
    h = math.radians(heading_deg)
    c, s = math.cos(h), math.sin(h)
    return points[:, 0] * c + points[:, 1] * s, -points[:, 0] * s + points[:, 1] * c


def _palm_spacing(points, crown):
    if len(points) < 2:
        return float(crown)
    d = np.hypot(points[:, None, 0] - points[None, :, 0], points[:, None, 1] - points[None, :, 1])
    np.fill_diagonal(d, np.inf)
    return float(np.median(d.min(axis=1)))


def _row_spacing_from_density(across, crown):
    """Median gap between the peaks of the across-row density (None with fewer than two peaks)."""
    sigma = BUNCH_SIGMA_CROWN * crown
    grid = np.arange(across.min() - 3 * sigma, across.max() + 3 * sigma, sigma / 4)
    density = np.exp(-(grid[:, None] - across[None, :]) ** 2 / (2 * sigma * sigma)).sum(axis=1)
    inner = density[1:-1]
    peaks = np.nonzero((inner > density[:-2]) & (inner >= density[2:]) & (inner >= 1.5))[0] + 1
    if len(peaks) < 2:
        return None
    return float(np.median(np.diff(grid[peaks])))


def _chain(along, across, tolerance, max_gap):
    """Greedy row tracking in order along the heading (module doc, step 2)."""
    rows = []  # [members], last member = the row's head
    for i in np.argsort(along, kind="stable"):
        best, best_d = None, tolerance
        for r, members in enumerate(rows):
            last = members[-1]
            if along[i] - along[last] > max_gap or along[i] == along[last]:
                continue
            d = abs(across[i] - _predicted_across(members, along, across, along[i]))
            if d <= best_d:
                best, best_d = r, d
        if best is None:
            rows.append([int(i)])
        else:
            rows[best].append(int(i))
    return [np.array(m) for m in rows]


def _predicted_across(members, along, across, at):
    """Where the row's line continues across at ``at``: the least-squares line of its last ``SLOPE_PALMS`` palms
    (a bend goes on bending; a single palm's row: level with it)."""
    last = members[-1]
    recent = members[-SLOPE_PALMS:]
    if len(recent) < 2:
        return across[last]
    a, c = along[recent], across[recent]
    spread = float(((a - a.mean()) ** 2).sum())
    if spread <= 1e-12:
        return across[last]
    slope = float(((a - a.mean()) * (c - c.mean())).sum()) / spread
    slope = max(-MAX_PREDICTED_SLOPE, min(MAX_PREDICTED_SLOPE, slope)) if len(recent) >= SLOPE_PALMS else 0.0
    return c.mean() + slope * (at - a.mean())


def _row_line(points, along, heading_deg, bend_tolerance):
    """Least-squares line from the first to the last palm, or a polyline through the bends."""
    centre = points.mean(axis=0)
    _, _, vt = np.linalg.svd(points - centre)
    direction = vt[0]
    h = math.radians(heading_deg)
    if direction @ (math.cos(h), math.sin(h)) < 0:
        direction = -direction
    t = (points - centre) @ direction
    normal = np.array([-direction[1], direction[0]])
    if np.abs((points - centre) @ normal).max() <= bend_tolerance:
        return (tuple(centre + t.min() * direction), tuple(centre + t.max() * direction))
    ordered = points[np.argsort(along, kind="stable")]
    keep = _douglas_peucker(ordered, bend_tolerance)
    return tuple(tuple(p) for p in ordered[keep])


def _douglas_peucker(points, tolerance):
    """Indices of the polyline vertices that keep every point within ``tolerance`` of it."""
    keep = {0, len(points) - 1}
    stack = [(0, len(points) - 1)]
    while stack:
        a, b = stack.pop()
        if b - a < 2:
            continue
        seg = points[b] - points[a]
        length = float(np.hypot(*seg)) or 1e-12
        rel = points[a + 1:b] - points[a]
        dist = np.abs(rel[:, 0] * seg[1] - rel[:, 1] * seg[0]) / length
        k = int(np.argmax(dist))
        if dist[k] > tolerance:
            keep.add(a + 1 + k)
            stack += [(a, a + 1 + k), (a + 1 + k, b)]
    return sorted(keep)


def _neighbour_spacing(rows, along, across, palm_spacing):
    """Median across-row distance between rows that are neighbours (adjacent by offset, overlapping along)."""
    gaps = []
    for r0, r1 in zip(rows[:-1], rows[1:]):
        a0, a1 = along[list(r0.members)], along[list(r1.members)]
        if min(a0.max(), a1.max()) - max(a0.min(), a1.min()) > -palm_spacing:
            gaps.append(r1.offset - r0.offset)
    gaps = [g for g in gaps if g > 0]
    return float(np.median(gaps)) if gaps else None
