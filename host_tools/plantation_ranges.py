"""The ranges a random plantation is drawn from (``PlantationRanges``, one (lo, hi) per parameter, checked so
that no drawn map can be ambiguous under the column rule) and the named profiles (``PROFILES``: ``wide``, the
default, and ``classic``). ``host_tools.plantation`` draws a map from them; its docstring says how the checks
keep every palm clear of the column rule."""
import dataclasses
import math
from dataclasses import dataclass

from crazyflie_app.app.navigation_core import NavigationParams
from host_tools.errors import ForaNavError
from host_tools.maps import ALTITUDE_RANGE_M, COLUMN_RULE_FACTOR

APP_CROWN_M = NavigationParams.crown_size_m  # the app's crownSize parameter (its default)
AMBIGUITY_MARGIN_M = 0.15
MIN_COLUMN_SLOT_M = 0.1  # a column is longer than its two end margins by at least this
MAX_TOTAL_TURN_DEG = 60.0  # the planting direction turns at most this much over a map (bends x bend)


@dataclass(frozen=True)
class PlantationRanges:
    """Each field: (lo, hi), drawn uniformly per map (integers: inclusive). The defaults are the ``wide``
    profile; ``PROFILES["classic"]`` holds the first generator's (the paper-like maps)."""
    columns: tuple = (1, 3)  # planting columns, flown as a serpentine
    column_length_m: tuple = (1.2, 5.0)
    column_spacing_m: tuple = (1.0, 5.0)  # between neighbouring columns
    tree_spacing_m: tuple = (0.45, 0.9)  # between neighbouring slots of a column
    crown_m: tuple = (0.28, 0.47)  # oil palm crown size, per tree
    lateral_jitter_m: tuple = (0.0, 0.12)  # per map: max |offset| of a tree from its column
    gap_rate: tuple = (0.0, 0.3)  # probability that a slot is empty
    cluster_rate: tuple = (0.0, 0.3)  # probability that a tree touches the previous one (crowns touching)
    lookalike_in_column_rate: tuple = (0.0, 0.2)  # probability that a slot holds a look-alike species
    lookalikes_beside: tuple = (0, 4)  # look-alike trees beside the columns
    off_column_palms: tuple = (0, 3)  # oil palms outside the column rule
    roofs: tuple = (0, 2)
    road_crossings: tuple = (0, 2)  # road crossings in a gap of a column (under the path)
    altitude_m: tuple = (0.9, 1.5)  # flight height
    heading_deg: tuple = (0.0, 360.0)  # direction of the first column, counter-clockwise from +x
    column_bends: tuple = (0, 3)  # bends of the planting direction along the columns (all columns alike)
    bend_deg: tuple = (0.0, 10.0)  # turn of the planting direction at each bend (sign drawn)
    column_offset_m: tuple = (0.0, 0.6)  # per map: max shift of a column's start along the planting direction
    column_end_margin_m: tuple = (-0.2, 0.45)  # first/last slot this far inside the column's ends (< 0: beyond)

    def validate(self) -> "PlantationRanges":
        for f in dataclasses.fields(self):
            lo, hi = getattr(self, f.name)
            if not (isinstance(lo, (int, float)) and isinstance(hi, (int, float))) or lo > hi:
                raise ForaNavError("plantation range %s: expected lo <= hi, got %r" % (f.name, (lo, hi)))
            if not (math.isfinite(lo) and math.isfinite(hi)):
                raise ForaNavError("plantation range %s: must be finite, got %r" % (f.name, (lo, hi)))
            if lo < 0 and f.name != "column_end_margin_m":
                raise ForaNavError("plantation range %s: must not be negative, got %r" % (f.name, (lo, hi)))
        for name in ("gap_rate", "cluster_rate", "lookalike_in_column_rate"):
            if getattr(self, name)[1] > 1:
                raise ForaNavError("plantation range %s: a probability, must be <= 1" % name)
        if self.columns[0] < 1 or self.crown_m[0] <= 0 or self.tree_spacing_m[0] <= 0:
            raise ForaNavError("plantation ranges: columns >= 1, crown_m and tree_spacing_m > 0")
        self._validate_sizes()
        max_jitter = min(COLUMN_RULE_FACTOR * self.crown_m[0], COLUMN_RULE_FACTOR * APP_CROWN_M) - AMBIGUITY_MARGIN_M
        if self.lateral_jitter_m[1] > max_jitter:
            raise ForaNavError("plantation range lateral_jitter_m: at most %.3f m with crown_m from %.2f m "
                               "(keeps palms clear of the column rule)" % (max_jitter, self.crown_m[0]))
        # a last (first) tree beyond the column's end (start) waypoint: still inside both rules with the margin
        overshoot = math.sqrt(max(0.0, max_jitter ** 2 - self.lateral_jitter_m[1] ** 2))
        if self.column_end_margin_m[0] < -overshoot:
            raise ForaNavError("plantation range column_end_margin_m: at least %.3f m with crown_m from %.2f m and "
                               "lateral_jitter_m up to %.2f m (a tree beyond the column's end stays clear of the "
                               "column rule)" % (-overshoot, self.crown_m[0], self.lateral_jitter_m[1]))
        # a column must hold a slot for a tree: its length at least both end margins (a column of length 0
        # made a map with no target at all)
        min_length = max(2.0 * self.column_end_margin_m[1], 0.0) + MIN_COLUMN_SLOT_M
        if self.column_length_m[0] < min_length:
            raise ForaNavError("plantation range column_length_m: at least %.2f m (a tree slot inside column_end_margin_m "
                               "up to %.2f m at each end), got %r" % (min_length, self.column_end_margin_m[1],
                                                                   self.column_length_m))
        # a palm of the next column must be outside the app's rule around this column's segment, also where
        # the planting direction has turned (the columns are shifted copies: closer by cos(turn) there)
        rule_and_margin = COLUMN_RULE_FACTOR * APP_CROWN_M + AMBIGUITY_MARGIN_M
        min_spacing = rule_and_margin / math.cos(math.radians(self.max_turn_deg)) + self.lateral_jitter_m[1]
        if self.columns[1] > 1 and self.column_spacing_m[0] < min_spacing - 1e-9:
            raise ForaNavError("plantation range column_spacing_m: at least %.3f m (rule + margin + jitter%s)"
                               % (min_spacing, ", turns of %.0f deg" % self.max_turn_deg if self.max_turn_deg else ""))
        return self

    def _validate_sizes(self):
        """Sizes whose extremes break the map or the flight, refused in one line."""
        lo, hi = ALTITUDE_RANGE_M
        if self.altitude_m[0] < lo or self.altitude_m[1] > hi:
            raise ForaNavError("plantation range altitude_m: must lie in %g..%g m (host_tools/maps.py), got %r"
                               % (lo, hi, self.altitude_m))
        for name, limit in (("columns", 20), ("column_length_m", 50.0), ("column_spacing_m", 50.0),
                            ("tree_spacing_m", 10.0), ("crown_m", 5.0), ("lookalikes_beside", 100),
                            ("off_column_palms", 100), ("roofs", 100), ("road_crossings", 100),
                            ("heading_deg", 360.0), ("column_bends", 10), ("bend_deg", 45.0),
                            ("column_offset_m", 10.0), ("column_end_margin_m", 5.0)):
            if getattr(self, name)[1] > limit:
                raise ForaNavError("plantation range %s: at most %g, got %r" % (name, limit, getattr(self, name)))
        if self.max_turn_deg > MAX_TOTAL_TURN_DEG:
            raise ForaNavError("plantation range bend_deg: column_bends x bend_deg at most %g deg, got %g"
                               % (MAX_TOTAL_TURN_DEG, self.max_turn_deg))

    @property
    def max_turn_deg(self) -> float:
        """The largest turn of the planting direction away from the first column's (every bend one way)."""
        return float(self.column_bends[1] * self.bend_deg[1])

    def with_overrides(self, **ranges: tuple[float, float]) -> "PlantationRanges":
        return dataclasses.replace(self, **ranges).validate()


PROFILES = {
    "wide": PlantationRanges(),
    "classic": PlantationRanges(column_length_m=(1.2, 2.4), column_spacing_m=(0.9, 1.2),
                                tree_spacing_m=(0.45, 0.65), crown_m=(0.30, 0.45), gap_rate=(0.0, 0.2),
                                lookalike_in_column_rate=(0.0, 0.1), lookalikes_beside=(0, 2),
                                off_column_palms=(0, 2), roofs=(0, 1), road_crossings=(0, 1),
                                altitude_m=(1.0, 1.5), heading_deg=(0.0, 0.0), column_bends=(0, 0),
                                bend_deg=(0.0, 0.0), column_offset_m=(0.0, 0.0), column_end_margin_m=(0.4, 0.4)),
}
DEFAULT_PROFILE = "wide"


def profile_of(ranges: PlantationRanges) -> tuple[str, list[str]]:
    """The profile ``ranges`` differ least from, and the names of the fields that differ from it."""
    def differing(name):
        base = PROFILES[name]
        return [f.name for f in dataclasses.fields(PlantationRanges)
                if tuple(getattr(ranges, f.name)) != tuple(getattr(base, f.name))]
    name = min(PROFILES, key=lambda n: (len(differing(n)), n != DEFAULT_PROFILE))
    return name, differing(name)
