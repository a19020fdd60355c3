"""Random plantations: serpentine planting columns with gaps, clusters, look-alikes, off-column palms, roofs
and road crossings, drawn from stated ranges by one seed.

    generate(seed, ranges=PlantationRanges()) -> (PlantationMap, factors dict)

Every parameter is a range (lo, hi) in ``PlantationRanges``; per map one value is drawn uniformly from each
range (integers inclusive), then the trees are placed with it. ``factors`` records the drawn values and what
was placed (for the sweep's breakdowns). Same seed and ranges, same map (same bytes once saved).

Two profiles (``plantation_ranges.PROFILES``, ``foranav plantation --profile``):

* ``wide`` (the default since issue 32): 1-3 columns 1-5 m apart, 1.2-5 m long (2-8+ trees), bent (up to 3
  bends of up to 10 degrees each), staggered (each column's start shifted by up to +-0.6 m), the first
  column heading anywhere (0-360 degrees), first and last trees from 0.2 m beyond the column's end waypoints
  (waypoints set by hand rarely sit exactly on the last tree) to 0.45 m inside them, crowns
  0.28-0.47 m, trees 0.45-0.9 m apart, more gaps and look-alikes, flown at 0.9-1.5 m.
* ``classic``: the first generator's ranges and its straight columns along +x. A seed gives the very map
  (same bytes) it gave before the wide profile existed, so the sweeps measured then replay with
  ``--profile classic``.

Layout: each column is placed in a local planting frame (x along the planting direction, y across it) as
straight slots, then ``_Warp`` maps the local frame onto the world: the planting direction turns at the
bends (every column is the same bent line, shifted across), then the whole map turns by the heading of the
first column. The new draws (heading, bends, offsets, end margin) come from a second random stream, so the
classic draws are untouched; the identity warp returns its input unchanged (no float rounding).

The column rule and how ambiguity is avoided
--------------------------------------------
A tree is a target iff it is an oil palm within 1.5 crown sizes of the path F (host_tools.maps). The app
applies the rule with its own crown parameter (app.crownSize 0.35 m, so 0.525 m) to its *estimate* of the
tree position, against the current segment. A tree close to the boundary could fall on either side, so the
generator keeps every oil palm clear of it by ``AMBIGUITY_MARGIN_M``:

* an oil palm in a column lies at most ``min(1.5 crown, 1.5 x APP_CROWN_M) - AMBIGUITY_MARGIN_M`` from the
  path (the lateral jitter range is capped to guarantee it; the check below enforces it);
* an oil palm off the column lies at least ``max(1.5 crown, 1.5 x APP_CROWN_M) + AMBIGUITY_MARGIN_M`` from
  every segment of the path (rejection sampling);
* columns are far enough apart (column_spacing x cos(the largest turn of the planting direction) >= the
  app's rule + margin, plus the jitter) that a palm of one column is outside the app's rule around its
  neighbours' segments;
* trees of other species are non-targets wherever they stand, so they may sit in the column (look-alikes).

A draw that cannot satisfy the checks (nothing fits) places fewer of the optional items; the map's targets
are then re-derived by the loader's rule and asserted equal to the intended ones.
"""
import math
from dataclasses import dataclass

import numpy as np

from crazyflie_app.app.navigation_core import NavigationParams
from host_tools.maps import (COLUMN_RULE_FACTOR, PlantationMap, Tree, WorldObject,
                             distance_to_path, in_planting_column, map_from_dict, map_to_dict)
from host_tools.plantation_ranges import AMBIGUITY_MARGIN_M, APP_CROWN_M, PROFILES, PlantationRanges

ROUNDING_SLACK_M = 1e-3  # positions are written to the mm: a palm can move this much against the rule
COLUMN_START_X_M = 0.3
LOOKALIKE_SPECIES = ("coconut", "date_palm", "citrus", "olive")
TOUCH_TOLERANCE_M = 0.02  # clustered crowns touch: centre distance = sum of radii + 0..this
CLEARANCE_M = 0.05  # free ground between crowns of items placed off the column grid
PLACEMENT_TRIES = 200
OFF_COLUMN_BAND_M = 0.35  # off-column palms lie within this of the nearest allowed distance (in or near view)
MIN_PIECE_M = 0.6  # bends of the planting direction at least this far apart (and from the column ends)
INTEGER_RANGES = ("columns", "lookalikes_beside", "off_column_palms", "roofs", "road_crossings", "column_bends")
GEOMETRY_RANGES = ("heading_deg", "column_bends", "bend_deg", "column_offset_m", "column_end_margin_m")
CAMERA_SCALE = NavigationParams.cam_scale  # m per px per m of height (a crown's size in pixels: the factors)
# The simulator renders a map's whole ground at once, at half a camera pixel (host_tools/sim/world.py), with
# a peak of ~45 bytes per mosaic pixel while it builds it: a map whose ground would exceed this many
# megapixels (estimated from its waypoints, everything placed beside them and the world's margin) is given
# fewer columns, down to the range's lowest. Only wide maps come near it: 3 columns 5 m apart, turned 45 deg,
# at 0.9 m would need ~80 Mpx (3.5 GB while building); with the cap the wide maps need at most ~41 Mpx.
MAX_GROUND_MPX = 60.0
BESIDE_REACH_M = 2.0  # beyond the path: off-column palms (<= 1.2 m), roofs (<= 0.95 m), their size


def _draw(rng, lo_hi, integer=False):
    lo, hi = lo_hi
    if integer:
        return int(rng.integers(int(lo), int(hi) + 1))
    return float(lo) if lo == hi else float(rng.uniform(lo, hi))


def _rule_m(crown_m):
    return COLUMN_RULE_FACTOR * crown_m, COLUMN_RULE_FACTOR * APP_CROWN_M


class _Warp:
    """The local planting frame (x along the planting direction, y across) -> the world.

    The planting direction turns by ``turn_deg`` at each local x in ``bend_xs`` (every column is the same
    bent line, shifted across it by its y), then the map turns by ``heading_deg`` about the origin."""

    def __init__(self, bend_xs=(), turns_deg=(), heading_deg=0.0):
        self.identity = not bend_xs and heading_deg == 0.0
        self.bend_xs = tuple(bend_xs)
        self.pieces = [(0.0, 0.0, 0.0, 0.0)]  # (local x where it starts, world x, y there, direction rad)
        direction = 0.0
        for x, turn in zip(bend_xs, turns_deg):
            x0, px, py, d = self.pieces[-1]
            direction += math.radians(turn)
            self.pieces.append((x, px + (x - x0) * math.cos(d), py + (x - x0) * math.sin(d), direction))
        self.cos_h, self.sin_h = math.cos(math.radians(heading_deg)), math.sin(math.radians(heading_deg))

    def __call__(self, x, y):
        if self.identity:
            return x, y
        x0, px, py, d = next(p for p in reversed(self.pieces) if x >= p[0] or p is self.pieces[0])
        bx, by = px + (x - x0) * math.cos(d), py + (x - x0) * math.sin(d) + y
        return bx * self.cos_h - by * self.sin_h, bx * self.sin_h + by * self.cos_h


class _Layout:
    """Trees and objects placed so far, with the overlap test."""

    def __init__(self):
        self.trees = []  # (x, y, species, crown_m), world
        self.objects = []  # WorldObject

    def free(self, x, y, radius_m, clearance=CLEARANCE_M):
        for tx, ty, _, crown in self.trees:
            if math.hypot(tx - x, ty - y) < radius_m + crown / 2.0 + clearance:
                return False
        for o in self.objects:
            if math.hypot(o.x - x, o.y - y) < radius_m + o.size_m / 2.0 + clearance:
                return False
        return True


@dataclass(frozen=True)
class _Geometry:
    """The draws of the second stream: where the columns lie."""
    warp: _Warp
    offsets: tuple  # per column: shift of its start along the planting direction (m)
    end_margin_m: float
    heading_deg: float
    bends: int
    max_turn_deg: float  # largest |turn| of the planting direction from the first column's


def _draw_geometry(seed, ranges, columns, length):
    rng = np.random.default_rng([int(seed), 0x6E0])
    heading = round(_draw(rng, ranges.heading_deg), 1) % 360.0
    bends = _draw(rng, ranges.column_bends, integer=True)
    bends = min(bends, max(0, int(length / MIN_PIECE_M) - 1))  # pieces at least MIN_PIECE_M long
    turns = [_draw(rng, ranges.bend_deg) * (1.0 if rng.random() < 0.5 else -1.0) for _ in range(bends)]
    bend_xs = [COLUMN_START_X_M + length * (k + 1) / (bends + 1) for k in range(bends)]
    offset = _draw(rng, ranges.column_offset_m)
    offsets = tuple(float(rng.uniform(-offset, offset)) if offset > 0 else 0.0 for _ in range(columns))
    end_margin = _draw(rng, ranges.column_end_margin_m)
    max_turn = max([abs(sum(turns[:k + 1])) for k in range(bends)] + [0.0])
    return _Geometry(_Warp(bend_xs, turns, heading), offsets, end_margin, heading, bends, max_turn)


def generate(seed: int, ranges: PlantationRanges | None = None) -> tuple[PlantationMap, dict]:
    """A random plantation (see the module docstring) -> (PlantationMap, factors)."""
    ranges = (ranges or PlantationRanges()).validate()
    rng = np.random.default_rng([int(seed), 0x91A7])
    d = {name: _draw(rng, getattr(ranges, name), name in INTEGER_RANGES)
         for name in ("columns", "column_length_m", "column_spacing_m", "tree_spacing_m", "lateral_jitter_m",
                      "gap_rate", "cluster_rate", "lookalike_in_column_rate", "lookalikes_beside",
                      "off_column_palms", "roofs", "road_crossings", "altitude_m")}
    geometry = _draw_geometry(seed, ranges, d["columns"], d["column_length_m"])
    waypoints, columns = _serpentine(d["columns"], d["column_length_m"], d["column_spacing_m"], geometry)
    while d["columns"] > max(1, ranges.columns[0]) and _ground_mpx(waypoints, d["altitude_m"]) > MAX_GROUND_MPX:
        d["columns"] -= 1  # the simulator could not hold the ground (see MAX_GROUND_MPX)
        waypoints, columns = _serpentine(d["columns"], d["column_length_m"], d["column_spacing_m"], geometry)
    layout = _Layout()
    counts = {"clusters": 0, "gaps": 0, "lookalikes_in_column": 0, "road_crossings": 0}
    gap_slots = []
    for y, x0, x1 in columns:
        _fill_column(rng, ranges, d, layout, (y, x0, x1), geometry, counts, gap_slots)
    _place_road_crossings(rng, d, layout, gap_slots, counts, geometry.heading_deg)
    placed_beside = _place_beside(rng, ranges, d, layout, waypoints, "lookalike", d["lookalikes_beside"])
    placed_off = _place_beside(rng, ranges, d, layout, waypoints, "off_column", d["off_column_palms"])
    placed_roofs = _place_beside(rng, ranges, d, layout, waypoints, "roof", d["roofs"])
    trees = []
    for i, (x, y, species, crown) in enumerate(layout.trees):
        target = species == "oil_palm" and in_planting_column(x, y, crown, waypoints)
        trees.append(Tree(i + 1, round(x, 3), round(y, 3), species, round(crown, 3), target))
    _check_unambiguous(trees, waypoints)
    altitude = round(d["altitude_m"], 3)
    pmap = PlantationMap("Random plantation seed %d" % seed, altitude, waypoints, tuple(trees),
                         tuple(layout.objects), seed=int(seed) % 100000, target_species="oil_palm")
    factors = {
        "columns": d["columns"], "column_length_m": round(d["column_length_m"], 3),
        "column_spacing_m": round(d["column_spacing_m"], 3), "tree_spacing_m": round(d["tree_spacing_m"], 3),
        "lateral_jitter_m": round(d["lateral_jitter_m"], 3), "altitude_m": altitude,
        "targets": sum(1 for t in trees if t.target), "gaps": counts["gaps"], "clusters": counts["clusters"],
        "lookalikes_in_column": counts["lookalikes_in_column"], "lookalikes_beside": placed_beside,
        "off_column_palms": placed_off, "roofs": placed_roofs, "road_crossings": counts["road_crossings"],
    }
    if any(tuple(getattr(ranges, name)) != tuple(getattr(PROFILES["classic"], name)) for name in GEOMETRY_RANGES):
        # only then: a classic map's factors (stored in sweep specs) keep their bytes
        palms = [t.crown_m for t in trees if t.species == "oil_palm"] or [0.0]
        factors.update({
            "heading_deg": geometry.heading_deg, "bends": geometry.bends,
            "max_turn_deg": round(geometry.max_turn_deg, 1),
            "column_offset_m": round(max([abs(o) for o in geometry.offsets] + [0.0]), 3),
            "column_end_margin_m": round(geometry.end_margin_m, 3),
            "crown_px_min": round(min(palms) / (CAMERA_SCALE * altitude), 1),
            "crown_px_max": round(max(palms) / (CAMERA_SCALE * altitude), 1),
        })
    return pmap, factors


def _ground_mpx(waypoints, altitude_m):
    """The simulator's mosaic of a map with these waypoints, estimated (megapixels)."""
    xs, ys = [p[0] for p in waypoints], [p[1] for p in waypoints]
    margin = BESIDE_REACH_M + 0.75 * altitude_m + 0.2
    metres_per_pixel = CAMERA_SCALE * altitude_m / 2.0
    return ((max(xs) - min(xs) + 2 * margin) * (max(ys) - min(ys) + 2 * margin)) / metres_per_pixel ** 2 / 1e6


def _serpentine(n_columns, length, spacing, geometry):
    """Waypoints (world) of n columns flown alternately forward and back, and each column in the local
    planting frame (y, x_start, x_end); a column's waypoints include the bends that lie inside it."""
    waypoints, columns = [], []
    y_top = spacing * (n_columns - 1) / 2.0
    for k in range(n_columns):
        x0 = COLUMN_START_X_M + geometry.offsets[k] if geometry.offsets[k] else COLUMN_START_X_M
        x1 = x0 + length
        y = round(y_top - k * spacing, 4)
        inside = [b for b in geometry.warp.bend_xs if x0 + 0.1 < b < x1 - 0.1]
        xs = [x0] + inside + [x1]
        for x in (xs if k % 2 == 0 else xs[::-1]):
            wx, wy = geometry.warp(x, y)
            waypoints.append((round(wx, 4), round(wy, 4)))
        columns.append((y, x0, x1))
    return tuple(waypoints), columns


def _fill_column(rng, ranges, d, layout, column, geometry, counts, gap_slots):
    y, x0, x1 = column
    warp = geometry.warp
    x = x0 + geometry.end_margin_m
    end = x1 - geometry.end_margin_m
    previous = None  # (x, crown, y, world x, world y) of the previous tree in this column
    while x <= end:
        crown = _draw(rng, ranges.crown_m)
        jitter = float(rng.uniform(-d["lateral_jitter_m"], d["lateral_jitter_m"]))
        roll_gap, roll_cluster, roll_lookalike = rng.random(), rng.random(), rng.random()
        species = "oil_palm"
        if roll_lookalike < d["lookalike_in_column_rate"]:
            species = LOOKALIKE_SPECIES[int(rng.integers(len(LOOKALIKE_SPECIES)))]
        if previous is not None and roll_cluster < d["cluster_rate"]:
            # crowns touching: move this tree up against the previous one
            x = previous[0] + (previous[1] + crown) / 2.0 + float(rng.uniform(0.0, TOUCH_TOLERANCE_M))
            jitter = previous[2] - y  # on the previous tree's line, so the two crowns meet
            counts["clusters"] += 1
        elif roll_gap < d["gap_rate"]:
            counts["gaps"] += 1
            gap_slots.append(warp(x, y))
            previous = None
            x += d["tree_spacing_m"]
            continue
        if x > end:
            break
        if previous is not None and x - previous[0] < (previous[1] + crown) / 2.0:
            x = previous[0] + (previous[1] + crown) / 2.0  # never overlapping
        wx, wy = warp(x, y + jitter)
        touching_m = (previous[1] + crown) / 2.0 - 1e-9 if previous is not None else 0.0
        while previous is not None and math.hypot(wx - previous[3], wy - previous[4]) < touching_m:
            # across a bend the crowns come closer than along the column (never on a straight column)
            x += 0.005
            wx, wy = warp(x, y + jitter)
        if x > end:
            break
        layout.trees.append((wx, wy, species, crown))
        counts["lookalikes_in_column"] += species != "oil_palm"
        previous = (x, crown, y + jitter, wx, wy)
        x += d["tree_spacing_m"]


def _place_road_crossings(rng, d, layout, gap_slots, counts, heading_deg):
    order = list(rng.permutation(len(gap_slots))) if gap_slots else []
    for index in order[:d["road_crossings"]]:
        x, y = gap_slots[int(index)]
        size = float(rng.uniform(0.35, 0.5))
        if layout.free(x, y, size / 2.0, clearance=0.0):
            yaw = float(rng.uniform(0, 90))
            layout.objects.append(WorldObject("road_cross", round(x, 3), round(y, 3), round(size, 3),
                                              round((yaw + heading_deg) % 360.0 if heading_deg else yaw, 1)))
            counts["road_crossings"] += 1


def _place_beside(rng, ranges, d, layout, waypoints, kind, count):
    """Rejection-sample ``count`` items of ``kind`` near but off the columns -> how many fitted."""
    xs = [p[0] for p in waypoints]
    ys = [p[1] for p in waypoints]
    box = (min(xs) - 0.8, max(xs) + 0.8, min(ys) - 1.2, max(ys) + 1.2)
    placed = 0
    for _ in range(count):
        for _try in range(PLACEMENT_TRIES):
            x, y = float(rng.uniform(box[0], box[1])), float(rng.uniform(box[2], box[3]))
            distance = distance_to_path(x, y, waypoints)
            if kind == "off_column":
                crown = _draw(rng, ranges.crown_m)
                low = max(_rule_m(crown)) + AMBIGUITY_MARGIN_M
                # judged as written (the map rounds to mm), so rounding cannot bring it inside the margin
                written = distance_to_path(round(x, 3), round(y, 3), waypoints)
                ok = (low <= distance <= low + OFF_COLUMN_BAND_M and max(_rule_m(round(crown, 3)))
                      + AMBIGUITY_MARGIN_M <= written and layout.free(x, y, crown / 2.0))
                item = (x, y, "oil_palm", crown)
            elif kind == "lookalike":
                crown = _draw(rng, ranges.crown_m)
                # beside the column: off the flown line but in view of it
                ok = crown / 2.0 + 0.1 <= distance <= 0.7 and layout.free(x, y, crown / 2.0)
                item = (x, y, LOOKALIKE_SPECIES[int(rng.integers(len(LOOKALIKE_SPECIES)))], crown)
            else:
                size = float(rng.uniform(0.4, 0.7))
                ok = size / 2.0 + 0.25 <= distance <= size / 2.0 + 0.6 and layout.free(x, y, size / 2.0)
                item = WorldObject("roof", round(x, 3), round(y, 3), round(size, 3),
                                   round(float(rng.uniform(0, 180)), 1))
            if ok:
                if kind == "roof":
                    layout.objects.append(item)
                else:
                    layout.trees.append(item)
                placed += 1
                break
    return placed


def _check_unambiguous(trees, waypoints):
    """Every oil palm clear of the column rule (both the map's and the app's) by the margin."""
    for tree in trees:
        if tree.species != "oil_palm":
            continue
        distance = distance_to_path(tree.x, tree.y, waypoints)
        inner, outer = min(_rule_m(tree.crown_m)), max(_rule_m(tree.crown_m))
        inside = distance <= inner - AMBIGUITY_MARGIN_M + ROUNDING_SLACK_M
        if not (inside or distance >= outer + AMBIGUITY_MARGIN_M - 1e-6):
            raise AssertionError("plantation: tree %d at %.3f m from the path is ambiguous" % (tree.id, distance))


def plantation_dict(seed: int, ranges: PlantationRanges | None = None) -> dict:
    """The map JSON object of ``generate(seed, ranges)`` (round-trips through the loader unchanged)."""
    pmap, _ = generate(seed, ranges)
    data = map_to_dict(pmap)
    reloaded = map_from_dict(data, source="<plantation>")
    assert reloaded.targets == pmap.targets
    return data
