"""Photo maps: a plantation map whose world is an aerial photograph and whose trees are its annotated crowns.

``build_photo_map(PhotoMapRequest(...))`` reads the photo and its boxes (the shared boxes CSV,
host_tools.annotations), sets the ground scale (``crown_m``: the median box becomes that crown size, default
the app's crownSize, so the photo becomes a floor mat as in the paper's indoor tests; or ``gsd_m``: metres per
photo pixel), places the photo centred on the world origin (photo up = world +x, photo left = world +y), fits
the planting rows through the box centres (host_tools.photo_rows), and returns the map JSON object and what was
found. The flight path F is the rows flown serpentine (or a subset: ``rows``), each row's line cut so that the
camera's whole view stays inside the photo while the MAV flies it, centres on any tree of its column or flies
a segment's reach beyond its end (``view_margins``); or the waypoints the user gives, in photo pixels.

Targets are written out by the app's own column rule: within columnFactor (1.5) x the app's crownSize
(0.35 m) of a segment of the path (crazyflie_app/app/path_following.py), not each photo crown's own size, since
the app knows one crown size.
The map stores the photo's path relative to the map file, its SHA-256 and the scale, and the row spacing
(``row_spacing_m``) the fit found.
"""
import hashlib
import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from crazyflie_app.app.nav_types import NavigationParams
from crazyflie_app.app.path_following import within_column
from host_tools import annotations, images
from host_tools.errors import ForaNavError
from host_tools.maps import (ALTITUDE_RANGE_M, COLUMN_RULE_FACTOR, MAX_COORDINATE_M, MAX_SIZE_M, SPECIES,
                             PhotoGround, Point, distance_to_path, map_from_dict, map_to_dict)
from host_tools.photo_rows import RowFit, fit_rows
from host_tools.sim.camera import CameraModel

APP_PARAMS = NavigationParams()
DEFAULT_CROWN_M = APP_PARAMS.crown_size_m  # the app's (and the paper's) crown size
DEFAULT_ALTITUDE_M = APP_PARAMS.altitude_m  # the paper's flight tests
MIN_ROW_LENGTH_CROWN = 1.0  # a row cut shorter than this by the photo's edge is not flown


@dataclass(frozen=True)
class PhotoMapRequest:
    photo: str
    boxes: str
    out: str  # where the map will be written (the photo's path is stored relative to its folder)
    label: str = "oil_palm"
    crown_m: float | None = None
    gsd_m: float | None = None
    altitude_m: float = DEFAULT_ALTITUDE_M
    heading_deg: float | None = None
    waypoints_px: tuple[Point, ...] | None = None
    rows: tuple[int, int] | None = None  # first and last row to fly (0-based, serpentine order), inclusive
    name: str = ""


@dataclass(frozen=True)
class PhotoMapResult:
    data: dict  # the map JSON object
    fit: RowFit | None  # None when the user gave the waypoints
    rows_flown: int
    rows_found: int
    targets: int
    trees: int
    metres_per_pixel: float
    row_spacing_m: float | None
    notes: tuple[str, ...] = field(default=())


def build_photo_map(req: PhotoMapRequest) -> PhotoMapResult:
    """The photo map of ``req`` (ForaNavError naming the file or option on bad input; writes nothing)."""
    data, image = images.read_image_file(req.photo)
    height_px, width_px = image.shape[:2]
    boxes = photo_boxes(req.boxes, req.photo, req.label, width_px, height_px)
    crown_px = float(np.median([(b.width + b.height) / 2.0 for b in boxes]))
    mpp = scale_from(req, crown_px)
    if not ALTITUDE_RANGE_M[0] <= req.altitude_m <= ALTITUDE_RANGE_M[1]:
        raise ForaNavError("--altitude: must be from %g to %g m, got %g" % (ALTITUDE_RANGE_M + (req.altitude_m,)))
    photo = PhotoGround(relative_path(req.photo, req.out), _sha256(data), mpp, width_px, height_px)
    if max(width_px, height_px) * mpp / 2 > MAX_COORDINATE_M:
        raise ForaNavError("--gsd/--crown-m: at %.4g m per pixel the photo would reach beyond +-%g m" % (mpp, MAX_COORDINATE_M))
    centres = np.array([photo.pixel_to_world(b.x_center, b.y_center) for b in boxes])
    crowns = np.array([(b.width + b.height) / 2.0 * mpp for b in boxes])
    if crowns.max() > MAX_SIZE_M:
        raise ForaNavError("--gsd/--crown-m: crowns up to %.3g m at this scale, more than %g m" % (crowns.max(), MAX_SIZE_M))
    inner = inner_rectangle(photo, req.altitude_m)
    fit, notes = None, []
    if req.waypoints_px is not None:
        waypoints = [photo.pixel_to_world(u, v) for u, v in req.waypoints_px]
        for i, (x, y) in enumerate(waypoints):
            if not _inside(inner, x, y):
                raise ForaNavError("--waypoints: waypoint %d (%g, %g px) takes the camera's view outside the photo "
                                   "(keep waypoints %.0f px from its left/right and %.0f px from its top/bottom edge)"
                                   % (i + 1, req.waypoints_px[i][0], req.waypoints_px[i][1],
                                      (inner[3] - photo.extent_m[3]) / -mpp, (inner[1] - photo.extent_m[1]) / -mpp))
        rows_found = rows_flown = 0
        spacing = None
    else:
        fit = fit_rows(centres, float(np.median(crowns)), req.heading_deg)
        lines = [clip_polyline(row.line, inner) for row in fit.rows]
        lines = [line for line in lines if line is not None and _length(line) >= MIN_ROW_LENGTH_CROWN * np.median(crowns)]
        rows_found = len(lines)
        if not lines:
            raise ForaNavError("%s: no planting row found (%d crowns of %s; a row needs 3 palms in line, inside the "
                               "part of the photo the camera can fly over at %g m)"
                               % (req.boxes, len(boxes), Path(req.photo).name, req.altitude_m))
        if req.rows is not None:
            first, last = req.rows
            if not 0 <= first <= last < len(lines):
                raise ForaNavError("--rows: %d:%d outside the %d rows found (0:%d)" % (first, last, len(lines),
                                                                                   len(lines) - 1))
            lines = lines[first:last + 1]
        waypoints = serpentine(lines)
        rows_flown = len(lines)
        spacing = round(fit.row_spacing, 4) if fit.row_spacing is not None else None
    trees = [{"id": i + 1, "x": round(float(x), 4), "y": round(float(y), 4), "species": req.label,
              "crown_m": round(float(c), 4), "target": app_column_target(float(x), float(y), waypoints, spacing or 0.0)}
             for i, ((x, y), c) in enumerate(zip(centres, crowns))]
    raw = {"name": req.name or Path(req.photo).stem, "altitude_m": req.altitude_m,
           "waypoints": [[round(float(x), 4), round(float(y), 4)] for x, y in waypoints], "trees": trees,
           "seed": 0, "target_species": req.label, "photo": _photo_dict(photo)}
    if spacing is not None:
        raw["row_spacing_m"] = spacing
    pmap = map_from_dict(raw, source=req.out)
    return PhotoMapResult(map_to_dict(pmap), fit, rows_flown, rows_found, len(pmap.targets), len(pmap.trees), mpp,
                          spacing, tuple(notes))


def app_column_target(x: float, y: float, waypoints: list[Point], row_spacing_m: float = 0.0) -> bool:
    """The app's own column rule: within columnFactor x its crownSize (not the photo's crown of that tree: the
    app knows one crown size) of a segment of the path, and never past half the row spacing (app.rowSpacing,
    which the flight sets from the map's row_spacing_m)."""
    xy = (round(x, 4), round(y, 4))
    path = [(round(float(a), 4), round(float(b), 4)) for a, b in waypoints]
    return within_column(distance_to_path(xy[0], xy[1], path), APP_PARAMS.crown_size_m, COLUMN_RULE_FACTOR,
                         row_spacing_m)


def photo_boxes(csv_path: str, photo: str, label: str, width_px: int, height_px: int) -> list[annotations.Box]:
    """The CSV's boxes of ``photo`` with ``label`` (refusing boxes of another image and boxes outside it)."""
    if label not in SPECIES:
        raise ForaNavError("--label: %r is no species a map can hold (%s)" % (label, ", ".join(SPECIES)))
    boxes = annotations.read_boxes(csv_path)
    folder = Path(csv_path).resolve().parent
    target = Path(photo).resolve()
    mine = [b for b in boxes if (folder / b.image).resolve() == target]
    if not mine:
        named = sorted({b.image for b in boxes})
        raise ForaNavError("%s: no box of %s (the CSV's images, relative to its folder: %s%s)"
                           % (csv_path, photo, ", ".join(named[:3]), " ..." if len(named) > 3 else ""))
    for b in mine:
        if b.label and not (0 <= b.x_center <= width_px and 0 <= b.y_center <= height_px):
            raise ForaNavError("%s: box of %s at (%g, %g) px lies outside the %dx%d photo (boxes of another image?)"
                               % (csv_path, b.image, b.x_center, b.y_center, width_px, height_px))
    chosen = [b for b in mine if b.label == label and b.width > 0 and b.height > 0]
    if not chosen:
        raise ForaNavError("%s: no box of %s has label %s (--label)" % (csv_path, photo, label))
    return chosen


def scale_from(req: PhotoMapRequest, crown_px: float) -> float:
    """Metres per photo pixel: --gsd, or --crown-m (default the app's crown size) over the median box."""
    if req.gsd_m is not None and req.crown_m is not None:
        raise ForaNavError("--gsd and --crown-m: give one of them")
    if req.gsd_m is not None:
        if not (req.gsd_m > 0 and math.isfinite(req.gsd_m)):
            raise ForaNavError("--gsd: must be a positive number of metres per pixel, got %r" % req.gsd_m)
        return float(req.gsd_m)
    crown_m = DEFAULT_CROWN_M if req.crown_m is None else req.crown_m
    if not (0 < crown_m <= MAX_SIZE_M):
        raise ForaNavError("--crown-m: must be from 0 to %g m, got %r" % (MAX_SIZE_M, crown_m))
    return float(crown_m) / crown_px


def view_margins(altitude_m: float) -> tuple[float, float]:
    """How far (x, y metres) the camera sees beyond a point the MAV may fly over, at yaw 0 (the app holds it):
    half the view, plus the column's half-width (the MAV centres on any tree of the column, and flies a
    segment's end reach, never more than that, beyond its end)."""
    camera = CameraModel()
    scale = camera.metres_per_pixel(altitude_m)
    reach = COLUMN_RULE_FACTOR * APP_PARAMS.crown_size_m
    return camera.height / 2.0 * scale + reach, camera.width / 2.0 * scale + reach


def inner_rectangle(photo: PhotoGround, altitude_m: float) -> tuple[float, float, float, float]:
    """(x_min, x_max, y_min, y_max): where the path may run with the camera's whole view inside the photo."""
    x_min, x_max, y_min, y_max = photo.extent_m
    mx, my = view_margins(altitude_m)
    return x_min + mx, x_max - mx, y_min + my, y_max - my


def clip_polyline(line: tuple[Point, ...], rect: tuple[float, float, float, float]) -> tuple[Point, ...] | None:
    """The longest connected part of a polyline inside an axis-aligned rectangle (None when nothing is)."""
    runs, current = [], []
    for a, b in zip(line[:-1], line[1:]):
        piece = _clip_segment(a, b, rect)
        if piece is None:
            if current:
                runs.append(current)
                current = []
            continue
        p, q = piece
        if current and math.hypot(current[-1][0] - p[0], current[-1][1] - p[1]) < 1e-9:
            current.append(q)
        else:
            if current:
                runs.append(current)
            current = [p, q]
    if current:
        runs.append(current)
    if not runs:
        return None
    return tuple(max(runs, key=_length))


def _clip_segment(a, b, rect):
    """Liang-Barsky: the part of segment a-b inside rect, or None."""
    x_min, x_max, y_min, y_max = rect
    if x_min > x_max or y_min > y_max:
        return None
    dx, dy = b[0] - a[0], b[1] - a[1]
    t0, t1 = 0.0, 1.0
    for p, q in ((-dx, a[0] - x_min), (dx, x_max - a[0]), (-dy, a[1] - y_min), (dy, y_max - a[1])):
        if p == 0:
            if q < 0:
                return None
            continue
        t = q / p
        if p < 0:
            t0 = max(t0, t)
        else:
            t1 = min(t1, t)
        if t0 > t1:
            return None
    return (a[0] + t0 * dx, a[1] + t0 * dy), (a[0] + t1 * dx, a[1] + t1 * dy)


def serpentine(lines: list[tuple[Point, ...]]) -> list[Point]:
    """The rows in order, every second one flown backwards."""
    path = []
    for k, line in enumerate(lines):
        path.extend(line if k % 2 == 0 else line[::-1])
    return path


def relative_path(photo: str, out: str) -> str:
    """The photo's path relative to the folder the map is written to (POSIX separators)."""
    return Path(os.path.relpath(Path(photo).resolve(), Path(out).resolve().parent)).as_posix()


def _photo_dict(photo: PhotoGround) -> dict:
    return {"path": photo.path, "sha256": photo.sha256, "metres_per_pixel": photo.metres_per_pixel,
            "width_px": photo.width_px, "height_px": photo.height_px}


def _sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _inside(rect, x, y):
    return rect[0] <= x <= rect[1] and rect[2] <= y <= rect[3]


def _length(line):
    return sum(math.hypot(b[0] - a[0], b[1] - a[1]) for a, b in zip(line[:-1], line[1:]))
