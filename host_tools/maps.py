"""Map files: the plantation a flight happens in. One definition, with a validating loader.

World frame in metres: x forward along the rows, y left, z up (the Crazyflie convention); yaw in degrees,
counter-clockwise seen from above.

A map is a JSON object:

    name            str      free text
    altitude_m      number   flight height above ground, ALTITUDE_RANGE_M (0.4 .. 4.5 m)
    waypoints       [[x, y], ...]   the flight path F: start and end of each planting column, flown in order (>= 2)
    trees           [{id, x, y, species, crown_m, target?}, ...]
    objects         [{kind, x, y, size_m, yaw_deg}, ...]       optional look-alikes: roof, road_cross
    seed            int      optional: ground texture and per-tree variation (default 0)
    target_species  str      optional: the species the mission targets (default oil_palm)
    row_spacing_m   number   optional: centre-to-centre distance between adjacent planting rows (m); the app
                             takes it as app.rowSpacing and its column rule never reaches past half of it
    photo           object   optional: the world is this photograph (a photo map, docs/photo-flights.md):
                             {path, sha256, metres_per_pixel, width_px, height_px}; ``path`` is relative to
                             the map file's folder; the photo's centre is the world origin, photo up is world
                             +x and photo left is world +y; trees are its annotated crowns, nothing is drawn

Coordinates lie within +-MAX_COORDINATE_M (1000 m), crown_m and size_m are at most MAX_SIZE_M (5 m).

``target`` is ground truth for scoring only (the flight app never reads it). When absent it is true iff the
species is the target species and the tree lies within ``COLUMN_RULE_FACTOR`` x ``crown_m`` of a path segment
(the paper's planting-column rule).

``load_map`` checks a photo map's photo: it must exist and have the checksum the map was written with (a
photo moved or changed since is refused).

Bad files raise ForaNavError with one line naming the file and the field, e.g.
``maps/x.json: trees[2].crown_m: must be a positive number``.
"""
import hashlib
import math
import os
import re
from collections.abc import Sequence
import dataclasses
from dataclasses import asdict, dataclass, field
from pathlib import Path

from crazyflie_app.app.nav_types import COLUMN_FACTOR
from crazyflie_app.app.path_following import distance_to_segment, within_column
from host_tools.errors import ForaNavError
from host_tools import fileio

SPECIES = ("oil_palm", "coconut", "date_palm", "citrus", "olive")
OBJECT_KINDS = ("roof", "road_cross")
COLUMN_RULE_FACTOR = COLUMN_FACTOR  # paper: trees farther than 1.5 crown sizes from the path are outside the column
BUILTIN_DIR = Path(__file__).resolve().parent / "data" / "maps"
MAX_SEED = 2 ** 32 - 1  # numpy's RandomState takes seeds up to this
Point = tuple[float, float]  # (x, y), m
MAX_INTEGER_NUMBER = 10 ** 15  # an integer beyond this in a map is a typo (and beyond 1e308 float() fails)
# The flight heights a map may state (m). The camera sees 0.0031 m per pixel per metre of height (352x288):
# below 0.4 m an app.crownSize crown (0.35 m) no longer fits the 288-px frame height, so the app cannot centre
# on it; above 4.5 m it spans fewer than the detector's smallest window (24 px). Refused outside (a map with
# 1e6 m made the simulator allocate terabytes and the app climb until the 900 s limit).
ALTITUDE_RANGE_M = (0.4, 4.5)
MAX_COORDINATE_M = 1000.0  # |x|, |y| of a waypoint, tree or object: at 0.1 m/s further is hours of flight
MAX_NAME_CHARS = 200  # a map's name: a plot title and a console line, not a document
# Trees and objects of a map: the oracle and the simulator look at every one each frame (9000 frames in a 900 s
# flight); 2000 trees took 60 s of CPU for one oracle flight here (issue 45), 100,000 never finished.
MAX_MAP_ITEMS = 1000
MAX_SIZE_M = 5.0  # crown_m, size_m: larger than the whole frame even at the highest altitude


@dataclass(frozen=True)
class Tree:
    id: int
    x: float
    y: float
    species: str
    crown_m: float
    target: bool


@dataclass(frozen=True)
class WorldObject:
    kind: str
    x: float
    y: float
    size_m: float
    yaw_deg: float = 0.0


@dataclass(frozen=True)
class PhotoGround:
    """The photograph a photo map's world is: centred on the world origin, photo up = world +x."""
    path: str  # as written in the map: relative to the map file's folder
    sha256: str  # hex digest of the photo file's bytes when the map was written
    metres_per_pixel: float  # ground size of one photo pixel
    width_px: int
    height_px: int
    resolved: str = field(default="", compare=False)  # the file it names (set by load_map)

    @property
    def extent_m(self) -> tuple[float, float, float, float]:
        """(x_min, x_max, y_min, y_max) of the photo in world metres."""
        half_x, half_y = self.height_px * self.metres_per_pixel / 2, self.width_px * self.metres_per_pixel / 2
        return -half_x, half_x, -half_y, half_y

    def pixel_to_world(self, col: float, row: float) -> Point:
        """World (x, y) of a continuous photo pixel (col, row)."""
        return ((self.height_px / 2.0 - row) * self.metres_per_pixel,
                (self.width_px / 2.0 - col) * self.metres_per_pixel)

    def world_to_pixel(self, x: float, y: float) -> tuple[float, float]:
        """Continuous photo pixel (col, row) of world (x, y)."""
        return self.width_px / 2.0 - y / self.metres_per_pixel, self.height_px / 2.0 - x / self.metres_per_pixel


@dataclass(frozen=True)
class PlantationMap:
    name: str
    altitude_m: float
    waypoints: tuple[Point, ...]
    trees: tuple[Tree, ...]
    objects: tuple[WorldObject, ...] = ()
    seed: int = 0
    target_species: str = "oil_palm"
    source: str = field(default="", compare=False)
    row_spacing_m: float = 0.0  # 0: the map does not give it
    photo: PhotoGround | None = None

    @property
    def targets(self) -> tuple[Tree, ...]:
        return tuple(t for t in self.trees if t.target)

    def tree(self, tree_id: int) -> Tree:
        for t in self.trees:
            if t.id == tree_id:
                return t
        raise KeyError(tree_id)


def distance_to_path(px: float, py: float, waypoints: Sequence[Point]) -> float:
    """Horizontal distance from point p to the nearest segment of the path (the app's segment geometry)."""
    return min(distance_to_segment(px, py, a, b) for a, b in zip(waypoints[:-1], waypoints[1:]))


def path_length_m(waypoints: Sequence[Point]) -> float:
    """Length of the path F (m)."""
    return sum(math.hypot(b[0] - a[0], b[1] - a[1]) for a, b in zip(waypoints[:-1], waypoints[1:]))


def in_planting_column(x: float, y: float, crown_m: float, waypoints: Sequence[Point],
                       row_spacing_m: float = 0.0) -> bool:
    """The app's planting-column rule, against every segment of the path (``row_spacing_m`` 0: not given)."""
    return within_column(distance_to_path(x, y, waypoints), crown_m, COLUMN_RULE_FACTOR, row_spacing_m)


# ----------------------------------------------------------------------------------------------------------
# Validation


class _Checker:
    def __init__(self, source):
        self.source = source

    def fail(self, where, message):
        raise ForaNavError("%s: %s: %s" % (self.source, where, message))

    def coordinate(self, obj, key, where):
        value = self.number(obj, key, where)
        if abs(value) > MAX_COORDINATE_M:
            self.fail(where + key, "must lie within +-%g m, got %r" % (MAX_COORDINATE_M, value))
        return value

    def size(self, obj, key, where):
        value = self.number(obj, key, where, positive=True)
        if value > MAX_SIZE_M:
            self.fail(where + key, "must be at most %g m, got %r" % (MAX_SIZE_M, value))
        return value

    def number(self, obj, key, where, positive=False, nonnegative=False):
        if key not in obj:
            self.fail(where + key, "missing")
        value = obj[key]
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            self.fail(where + key, "must be a number, got %s" % type(value).__name__)
        if isinstance(value, int) and abs(value) > MAX_INTEGER_NUMBER:
            self.fail(where + key, "number too large")
        if not math.isfinite(value):
            self.fail(where + key, "must be finite, got %r" % value)
        if positive and value <= 0:
            self.fail(where + key, "must be a positive number, got %r" % value)
        if nonnegative and value < 0:
            self.fail(where + key, "must not be negative, got %r" % value)
        return float(value)

    def integer(self, obj, key, where):
        value = obj.get(key)
        if isinstance(value, bool) or not isinstance(value, int):
            self.fail(where + key, "must be an integer, got %s" % type(value).__name__)
        return value

    def string(self, obj, key, where, choices=None):
        if key not in obj:
            self.fail(where + key, "missing")
        value = obj[key]
        if not isinstance(value, str):
            self.fail(where + key, "must be a string, got %s" % type(value).__name__)
        if choices is not None and value not in choices:
            self.fail(where + key, "unknown value %r (expected one of %s)" % (value, ", ".join(choices)))
        return value

    def fields(self, obj, where, required, optional=()):
        if not isinstance(obj, dict):
            self.fail(where.rstrip(".") or "map", "must be an object")
        for key in obj:
            if key not in required and key not in optional:
                self.fail(where + key, "unknown field")
        for key in required:
            if key not in obj:
                self.fail(where + key, "missing")

    def array(self, obj, key, where):
        value = obj[key]
        if not isinstance(value, list):
            self.fail(where + key, "must be an array")
        return value


def map_from_dict(data: dict, source: str = "<map>") -> PlantationMap:
    """Validate a decoded JSON object and build a PlantationMap."""
    c = _Checker(source)
    c.fields(data, "", ("name", "altitude_m", "waypoints", "trees"),
             ("objects", "seed", "target_species", "row_spacing_m", "photo"))
    name = c.string(data, "name", "")
    if len(name) > MAX_NAME_CHARS:
        c.fail("name", "a name of %d characters; at most %d" % (len(name), MAX_NAME_CHARS))
    for key in ("trees", "objects"):
        if isinstance(data.get(key), list) and len(data[key]) > MAX_MAP_ITEMS:
            c.fail(key, "%d %s; a map holds at most %d" % (len(data[key]), key, MAX_MAP_ITEMS))
    altitude = c.number(data, "altitude_m", "", positive=True)
    if not ALTITUDE_RANGE_M[0] <= altitude <= ALTITUDE_RANGE_M[1]:
        c.fail("altitude_m", "must be from %g to %g m (a flight height the camera can work at), got %r"
               % (ALTITUDE_RANGE_M + (altitude,)))
    target_species = c.string(data, "target_species", "", SPECIES) if "target_species" in data else "oil_palm"
    seed = c.integer(data, "seed", "") if "seed" in data else 0
    if not 0 <= seed <= MAX_SEED:
        c.fail("seed", "must be an integer from 0 to %d, got %d" % (MAX_SEED, seed))

    row_spacing = c.number(data, "row_spacing_m", "", positive=True) if "row_spacing_m" in data else 0.0
    if row_spacing > MAX_COORDINATE_M:
        c.fail("row_spacing_m", "must be at most %g m, got %r" % (MAX_COORDINATE_M, row_spacing))

    raw_wps = c.array(data, "waypoints", "")
    if len(raw_wps) < 2:
        c.fail("waypoints", "needs at least 2 waypoints, got %d" % len(raw_wps))
    waypoints = []
    for i, wp in enumerate(raw_wps):
        if not isinstance(wp, list) or len(wp) != 2:
            c.fail("waypoints[%d]" % i, "must be [x, y]")
        waypoints.append((c.coordinate({"x": wp[0]}, "x", "waypoints[%d]." % i),
                          c.coordinate({"y": wp[1]}, "y", "waypoints[%d]." % i)))
    waypoints = tuple(waypoints)

    trees, seen = [], set()
    for i, t in enumerate(c.array(data, "trees", "")):
        where = "trees[%d]." % i
        c.fields(t, where, ("id", "x", "y", "species", "crown_m"), ("target",))
        tree_id = c.integer(t, "id", where)
        if tree_id in seen:
            c.fail(where + "id", "duplicate id %d" % tree_id)
        seen.add(tree_id)
        x, y = c.coordinate(t, "x", where), c.coordinate(t, "y", where)
        species = c.string(t, "species", where, SPECIES)
        crown = c.size(t, "crown_m", where)
        if "target" in t:
            if not isinstance(t["target"], bool):
                c.fail(where + "target", "must be true or false")
            target = t["target"]
        else:
            target = species == target_species and in_planting_column(x, y, crown, waypoints, row_spacing)
        trees.append(Tree(tree_id, x, y, species, crown, target))

    objects = []
    for i, o in enumerate(c.array(data, "objects", "") if "objects" in data else []):
        where = "objects[%d]." % i
        c.fields(o, where, ("kind", "x", "y", "size_m"), ("yaw_deg",))
        objects.append(WorldObject(c.string(o, "kind", where, OBJECT_KINDS), c.coordinate(o, "x", where),
                                   c.coordinate(o, "y", where), c.size(o, "size_m", where),
                                   c.number(o, "yaw_deg", where) if "yaw_deg" in o else 0.0))
    photo = _photo(c, data["photo"]) if "photo" in data else None
    return PlantationMap(name, altitude, waypoints, tuple(trees), tuple(objects), seed, target_species, source,
                         row_spacing, photo)


SHA256_HEX = re.compile(r"^[0-9a-f]{64}$")
MAX_PHOTO_SIDE_PX = 65536  # annotations.MAX_BOX_PX: no photo we read is larger


def _photo(c: _Checker, data: object) -> PhotoGround:
    where = "photo."
    c.fields(data, where, ("path", "sha256", "metres_per_pixel", "width_px", "height_px"))
    path = c.string(data, "path", where)
    if not path:
        c.fail(where + "path", "must not be empty")
    digest = c.string(data, "sha256", where)
    if not SHA256_HEX.match(digest):
        c.fail(where + "sha256", "must be 64 lower-case hex digits")
    mpp = c.number(data, "metres_per_pixel", where, positive=True)
    sides = []
    for key in ("width_px", "height_px"):
        value = c.integer(data, key, where)
        if not 1 <= value <= MAX_PHOTO_SIDE_PX:
            c.fail(where + key, "must be from 1 to %d, got %d" % (MAX_PHOTO_SIDE_PX, value))
        sides.append(value)
    if max(sides) * mpp / 2 > MAX_COORDINATE_M:
        c.fail(where + "metres_per_pixel", "the photo would reach beyond +-%g m" % MAX_COORDINATE_M)
    return PhotoGround(path, digest, mpp, sides[0], sides[1])


def file_sha256(path: str | os.PathLike) -> str:
    """Hex SHA-256 of a file's bytes (ForaNavError naming it when it cannot be read)."""
    digest = hashlib.sha256()
    try:
        with open(path, "rb") as handle:
            for block in iter(lambda: handle.read(1 << 20), b""):
                digest.update(block)
    except OSError as err:
        raise ForaNavError("%s: cannot read: %s" % (path, err.strerror or err))
    return digest.hexdigest()


def resolve_photo(pmap: PlantationMap, map_path: str | os.PathLike) -> PlantationMap:
    """The map with its photo's file resolved next to the map file and checked against the checksum."""
    if pmap.photo is None:
        return pmap
    photo_path = Path(map_path).resolve().parent / pmap.photo.path
    if not photo_path.is_file():
        raise ForaNavError("%s: photo.path: %s not found (moved since the map was written?)" % (map_path, photo_path))
    if file_sha256(photo_path) != pmap.photo.sha256:
        raise ForaNavError("%s: photo.sha256: %s has changed since the map was written (checksum differs)"
                           % (map_path, photo_path))
    return dataclasses.replace(pmap, photo=dataclasses.replace(pmap.photo, resolved=str(photo_path)))


def map_to_dict(pmap: PlantationMap) -> dict:
    """The JSON object of a map (targets written out explicitly)."""
    data = {"name": pmap.name, "altitude_m": pmap.altitude_m,
            "waypoints": [list(wp) for wp in pmap.waypoints],
            "trees": [asdict(t) for t in pmap.trees]}
    if pmap.objects:
        data["objects"] = [asdict(o) for o in pmap.objects]
    data["seed"] = pmap.seed
    data["target_species"] = pmap.target_species
    if pmap.row_spacing_m > 0.0:  # only when given: maps without it keep their bytes
        data["row_spacing_m"] = pmap.row_spacing_m
    if pmap.photo is not None:
        photo = asdict(pmap.photo)
        # a loaded map handed on (a sweep's worker, the realtime camera process, a clip) names the file it
        # was checked against; a map written by `foranav plantation` names it relative to its own folder
        photo["path"] = photo.pop("resolved") or photo["path"]
        data["photo"] = photo
    return data


def builtin_map_names() -> list[str]:
    return sorted(p.stem for p in BUILTIN_DIR.glob("*.json"))


def resolve_map_path(name_or_path: str | os.PathLike) -> Path:
    """A path to a map file, or the name of a built-in map (map1, map2, map3, ...)."""
    path = Path(name_or_path)
    if path.suffix == "" and not path.exists():
        candidate = BUILTIN_DIR / (str(name_or_path) + ".json")
        if candidate.exists():
            return candidate
        raise ForaNavError("%s: no such map file or built-in map (built-in: %s)"
                           % (name_or_path, ", ".join(builtin_map_names())))
    return path


def load_map(name_or_path: str | os.PathLike) -> PlantationMap:
    """Load and validate a map file (or a built-in map by name)."""
    path = resolve_map_path(name_or_path)
    data = fileio.read_json(path, "map file", parse_constant=lambda c: float("nan"))
    return resolve_photo(map_from_dict(data, str(path)), path)


def save_map(pmap: PlantationMap, path: str | os.PathLike) -> None:
    fileio.write_json(path, map_to_dict(pmap))
