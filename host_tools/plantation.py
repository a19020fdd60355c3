"""Random plantations: serpentine planting columns with gaps, clusters, look-alikes, off-column palms, roofs
and road crossings, drawn from stated ranges by one seed.

    generate(seed, ranges=PlantationRanges()) -> (PlantationMap, factors dict)

Every parameter is a range (lo, hi) in ``PlantationRanges``; per map one value is drawn uniformly from each
range (integers inclusive), then the trees are placed with it. ``factors`` records the drawn values and what
was placed (for the sweep's breakdowns). Same seed and ranges, same map (same bytes once saved).

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
* columns are far enough apart (column_spacing >= the app's rule + margin + jitter) that a palm of one
  column is outside the app's rule around its neighbours' segments;
* trees of other species are non-targets wherever they stand, so they may sit in the column (look-alikes).

A draw that cannot satisfy the checks (nothing fits) places fewer of the optional items; the map's targets
are then re-derived by the loader's rule and asserted equal to the intended ones.
"""
import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from crazyflie_app.navigation_core import NavigationParams
from host_tools.errors import ForaNavError
from host_tools.maps import (COLUMN_RULE_FACTOR, PlantationMap, Tree, WorldObject, distance_to_path, in_planting_column,
                             map_from_dict)
from host_tools.maps import map_to_dict

APP_CROWN_M = NavigationParams.crown_size_m  # the app's crownSize parameter (its default)
AMBIGUITY_MARGIN_M = 0.15
COLUMN_START_X_M = 0.3
COLUMN_END_MARGIN_M = 0.4  # first/last slot this far inside the column's ends (clear of the turn segments)
LOOKALIKE_SPECIES = ("coconut", "date_palm", "citrus", "olive")
TOUCH_TOLERANCE_M = 0.02  # clustered crowns touch: centre distance = sum of radii + 0..this
CLEARANCE_M = 0.05  # free ground between crowns of items placed off the column grid
PLACEMENT_TRIES = 200
OFF_COLUMN_BAND_M = 0.35  # off-column palms lie within this of the nearest allowed distance (in or near view)
INTEGER_RANGES = ("columns", "lookalikes_beside", "off_column_palms", "roofs", "road_crossings")


@dataclass(frozen=True)
class PlantationRanges:
    """Each field: (lo, hi), drawn uniformly per map (integers: inclusive). Defaults resemble the paper maps."""
    columns: tuple = (1, 3)  # planting columns, flown as a serpentine
    column_length_m: tuple = (1.2, 2.4)
    column_spacing_m: tuple = (0.9, 1.2)  # between neighbouring columns
    tree_spacing_m: tuple = (0.45, 0.65)  # between neighbouring slots of a column
    crown_m: tuple = (0.30, 0.45)  # oil palm crown size, per tree
    lateral_jitter_m: tuple = (0.0, 0.12)  # per map: max |offset| of a tree from its column
    gap_rate: tuple = (0.0, 0.2)  # probability that a slot is empty
    cluster_rate: tuple = (0.0, 0.3)  # probability that a tree touches the previous one (crowns touching)
    lookalike_in_column_rate: tuple = (0.0, 0.1)  # probability that a slot holds a look-alike species
    lookalikes_beside: tuple = (0, 2)  # look-alike trees beside the columns
    off_column_palms: tuple = (0, 2)  # oil palms outside the column rule
    roofs: tuple = (0, 1)
    road_crossings: tuple = (0, 1)  # road crossings in a gap of a column (under the path)
    altitude_m: tuple = (1.0, 1.5)  # flight height

    def validate(self) -> "PlantationRanges":
        for f in dataclasses.fields(self):
            lo, hi = getattr(self, f.name)
            if not (isinstance(lo, (int, float)) and isinstance(hi, (int, float))) or lo > hi:
                raise ForaNavError("plantation range %s: expected lo <= hi, got %r" % (f.name, (lo, hi)))
            if lo < 0:
                raise ForaNavError("plantation range %s: must not be negative, got %r" % (f.name, (lo, hi)))
        for name in ("gap_rate", "cluster_rate", "lookalike_in_column_rate"):
            if getattr(self, name)[1] > 1:
                raise ForaNavError("plantation range %s: a probability, must be <= 1" % name)
        if self.columns[0] < 1 or self.altitude_m[0] <= 0 or self.crown_m[0] <= 0 or self.tree_spacing_m[0] <= 0:
            raise ForaNavError("plantation ranges: columns >= 1, altitude_m, crown_m and tree_spacing_m > 0")
        max_jitter = min(COLUMN_RULE_FACTOR * self.crown_m[0], COLUMN_RULE_FACTOR * APP_CROWN_M) - AMBIGUITY_MARGIN_M
        if self.lateral_jitter_m[1] > max_jitter:
            raise ForaNavError("plantation range lateral_jitter_m: at most %.3f m with crown_m from %.2f m "
                               "(keeps palms clear of the column rule)" % (max_jitter, self.crown_m[0]))
        # a palm of the next column must be outside the app's rule around this column's segment
        min_spacing = COLUMN_RULE_FACTOR * APP_CROWN_M + AMBIGUITY_MARGIN_M + self.lateral_jitter_m[1]
        if self.columns[1] > 1 and self.column_spacing_m[0] < min_spacing:
            raise ForaNavError("plantation range column_spacing_m: at least %.3f m (rule + margin + jitter)"
                               % min_spacing)
        return self

    def with_overrides(self, **ranges: tuple[float, float]) -> "PlantationRanges":
        return dataclasses.replace(self, **ranges).validate()


def _draw(rng, lo_hi, integer=False):
    lo, hi = lo_hi
    if integer:
        return int(rng.integers(int(lo), int(hi) + 1))
    return float(lo) if lo == hi else float(rng.uniform(lo, hi))


def _rule_m(crown_m):
    return COLUMN_RULE_FACTOR * crown_m, COLUMN_RULE_FACTOR * APP_CROWN_M


class _Layout:
    """Trees and objects placed so far, with the overlap test."""

    def __init__(self):
        self.trees = []  # (x, y, species, crown_m)
        self.objects = []  # WorldObject

    def free(self, x, y, radius_m, clearance=CLEARANCE_M):
        for tx, ty, _, crown in self.trees:
            if math.hypot(tx - x, ty - y) < radius_m + crown / 2.0 + clearance:
                return False
        for o in self.objects:
            if math.hypot(o.x - x, o.y - y) < radius_m + o.size_m / 2.0 + clearance:
                return False
        return True


def generate(seed: int, ranges: PlantationRanges | None = None) -> tuple[PlantationMap, dict]:
    """A random plantation (see the module docstring) -> (PlantationMap, factors)."""
    ranges = (ranges or PlantationRanges()).validate()
    rng = np.random.default_rng([int(seed), 0x91A7])
    d = {name: _draw(rng, getattr(ranges, name), name in INTEGER_RANGES)
         for name in ("columns", "column_length_m", "column_spacing_m", "tree_spacing_m", "lateral_jitter_m",
                      "gap_rate", "cluster_rate", "lookalike_in_column_rate", "lookalikes_beside",
                      "off_column_palms", "roofs", "road_crossings", "altitude_m")}
    waypoints, columns = _serpentine(d["columns"], d["column_length_m"], d["column_spacing_m"])
    layout = _Layout()
    counts = {"clusters": 0, "gaps": 0, "lookalikes_in_column": 0, "road_crossings": 0}
    gap_slots = []
    for y, x0, x1 in columns:
        _fill_column(rng, ranges, d, layout, y, x0, x1, counts, gap_slots)
    _place_road_crossings(rng, d, layout, gap_slots, counts)
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
    return pmap, factors


def _serpentine(n_columns, length, spacing):
    """Waypoints of n columns flown alternately forward and back, and each column (y, x_start, x_end)."""
    waypoints, columns = [], []
    y_top = spacing * (n_columns - 1) / 2.0
    x0, x1 = COLUMN_START_X_M, COLUMN_START_X_M + length
    for k in range(n_columns):
        y = round(y_top - k * spacing, 4)
        ends = (x0, x1) if k % 2 == 0 else (x1, x0)
        waypoints.extend([(round(ends[0], 4), y), (round(ends[1], 4), y)])
        columns.append((y, x0, x1))
    return tuple(waypoints), columns


def _fill_column(rng, ranges, d, layout, y, x0, x1, counts, gap_slots):
    x = x0 + COLUMN_END_MARGIN_M
    end = x1 - COLUMN_END_MARGIN_M
    previous = None  # (x, crown, y) of the previous tree in this column
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
            gap_slots.append((x, y))
            previous = None
            x += d["tree_spacing_m"]
            continue
        if x > end:
            break
        if previous is not None and x - previous[0] < (previous[1] + crown) / 2.0:
            x = previous[0] + (previous[1] + crown) / 2.0  # never overlapping
        layout.trees.append((x, y + jitter, species, crown))
        counts["lookalikes_in_column"] += species != "oil_palm"
        previous = (x, crown, y + jitter)
        x += d["tree_spacing_m"]


def _place_road_crossings(rng, d, layout, gap_slots, counts):
    order = list(rng.permutation(len(gap_slots))) if gap_slots else []
    for index in order[:d["road_crossings"]]:
        x, y = gap_slots[int(index)]
        size = float(rng.uniform(0.35, 0.5))
        if layout.free(x, y, size / 2.0, clearance=0.0):
            layout.objects.append(WorldObject("road_cross", round(x, 3), round(y, 3), round(size, 3),
                                              round(float(rng.uniform(0, 90)), 1)))
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
        if not (distance <= inner - AMBIGUITY_MARGIN_M + 1e-6 or distance >= outer + AMBIGUITY_MARGIN_M - 1e-6):
            raise AssertionError("plantation: tree %d at %.3f m from the path is ambiguous" % (tree.id, distance))


def plantation_dict(seed: int, ranges: PlantationRanges | None = None) -> dict:
    """The map JSON object of ``generate(seed, ranges)`` (round-trips through the loader unchanged)."""
    pmap, _ = generate(seed, ranges)
    data = map_to_dict(pmap)
    reloaded = map_from_dict(data, source="<plantation>")
    assert reloaded.targets == pmap.targets
    return data
