"""Write a random plantation map: serpentine planting columns with gaps, clusters, look-alike species,
off-column oil palms, roofs and road crossings, and a flight height, all drawn from ranges by one seed.

Two profiles: wide (the default: bent, staggered, turned columns 1-5 m apart, 2-8+ trees a column, crowns
0.28-0.47 m, flown at 0.9-1.5 m) and classic (the first generator's straight columns along +x: a seed gives
the map it gave before the wide profile existed). Every range option takes LO:HI (or one value) and
overrides the profile's range; the defaults of both profiles are listed with each option. Oil palms are
never placed where the planting-column rule is ambiguous: a palm in a column lies at least 0.15 m inside
both the map's rule (1.5 x its crown) and the app's (1.5 x app.crownSize 0.35 m); an off-column palm at
least 0.15 m outside both (see host_tools/plantation.py).

Prints the map JSON (or, with --out, writes it there and prints one line with what was drawn). Same seed
and options, same bytes.

With --photo, the map's world is an aerial photograph (true-colour nadir photo or orthomosaic tile, JPEG/PNG)
and its trees are the photo's boxes in --boxes (the shared boxes CSV): the photo is scaled so that the median
box is --crown-m (default the app's crown size 0.35 m: the photo becomes a floor mat) or to --gsd metres per
pixel, planting rows are fitted through the box centres (any heading, gaps, bends, triangular planting; or
--heading), and the path F flies them serpentine (or --rows I:J of them; or --waypoints in photo pixels),
kept so that the camera's view stays inside the photo. Targets follow the app's column rule. The map stores
the photo's path (relative to the map), its SHA-256, the scale and the row spacing (docs/photo-flights.md).

Examples:
  foranav plantation --seed 7 --out runs/p7.json
  foranav plantation --seed 7 --columns 3 --altitude-m 1.0 --off-column-palms 2 --out p.json
  foranav plantation --seed 7 --profile classic --out p.json      # the map seed 7 gave before
  foranav fly --map runs/p7.json --camera oracle
  foranav plantation --photo estate/Stani_01.jpg --boxes estate/boxes.csv --out runs/stani01.json
  foranav plantation --photo tile.png --boxes boxes.csv --gsd 0.004 --altitude 1.0 --rows 2:3 --out p.json
"""
import argparse
import dataclasses
import json
import math
import re

from host_tools import argtypes, fileio
from host_tools.errors import ForaNavError
from host_tools.photo_map import PhotoMapRequest, build_photo_map
from host_tools.plantation import INTEGER_RANGES, generate, plantation_dict
from host_tools.plantation_ranges import DEFAULT_PROFILE, PROFILES, PlantationRanges


def add_range_arguments(parser: argparse.ArgumentParser) -> None:
    """--profile, and one --<range> option per PlantationRanges field (LO:HI or a value)."""
    parser.add_argument("--profile", choices=sorted(PROFILES), default=DEFAULT_PROFILE,
                        help="the ranges the options below override (default %s; classic: the first "
                             "generator's maps, seed for seed)" % DEFAULT_PROFILE)
    for f in dataclasses.fields(PlantationRanges):
        lo, hi = getattr(PROFILES[DEFAULT_PROFILE], f.name)
        classic = "%s:%s" % getattr(PROFILES["classic"], f.name)
        parser.add_argument("--" + f.name.replace("_", "-"), metavar="LO:HI", default=None,
                            help="range of %s (default %s:%s; classic %s)" % (f.name, lo, hi, classic))


def ranges_from_args(args: argparse.Namespace) -> PlantationRanges:
    """The profile's PlantationRanges with the given options applied (ForaNavError naming a bad option)."""
    overrides = {}
    for f in dataclasses.fields(PlantationRanges):
        text = getattr(args, f.name, None)
        if text is None:
            continue
        option = "--" + f.name.replace("_", "-")
        cast = int if f.name in INTEGER_RANGES else float
        try:
            parts = [cast(p) for p in str(text).split(":")]
        except ValueError:
            raise ForaNavError("%s: expected LO:HI or one %s, got %r"
                               % (option, "integer" if cast is int else "number", text))
        if len(parts) not in (1, 2):
            raise ForaNavError("%s: expected LO:HI or one value, got %r" % (option, text))
        overrides[f.name] = (parts[0], parts[-1])
    try:
        return PROFILES[getattr(args, "profile", DEFAULT_PROFILE)].with_overrides(**overrides)
    except ForaNavError as err:  # name the option, not the field
        raise ForaNavError(re.sub(r"^plantation ranges?:? ?(\w+)?",
                                  lambda m: "--" + m.group(1).replace("_", "-") if m.group(1) else "ranges",
                                  str(err)))


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--seed", type=argtypes.seed, default=0, help="seed of every random choice (default 0)")
    parser.add_argument("--out", help="write the map here (default: print it; required with --photo)")
    add_range_arguments(parser)
    photo = parser.add_argument_group("photo maps (the world is an aerial photograph)")
    photo.add_argument("--photo", metavar="IMAGE", help="the photo (JPEG/PNG) whose boxes become the map's trees")
    photo.add_argument("--boxes", metavar="CSV", help="boxes CSV listing the photo's crowns (required with --photo)")
    photo.add_argument("--label", default="oil_palm", help="the boxes' label to take as trees (default oil_palm)")
    # --crown-m (above, a range for random maps) is the scale with --photo: the median box becomes a crown of
    # that many metres (default the app's crownSize 0.35)
    photo.add_argument("--gsd", type=argtypes.positive, metavar="M_PER_PX",
                       help="scale: metres per photo pixel (instead of --crown-m M: the median box becomes a crown "
                            "of M metres; default the app's crownSize 0.35)")
    photo.add_argument("--altitude", type=argtypes.positive, metavar="M", default=None,
                       help="flight height (default 1.25 m, the paper's)")
    photo.add_argument("--heading", type=argtypes.finite, metavar="DEG",
                       help="the rows' direction in the photo, degrees counter-clockwise from photo up "
                            "(default: the direction with the best support)")
    photo.add_argument("--rows", metavar="I:J", help="fly only rows I to J (0-based, in the order found)")
    photo.add_argument("--waypoints", nargs="+", metavar="U,V", help="fly these photo pixels instead of the rows")


def run(args: argparse.Namespace) -> int:
    if args.photo is not None or args.boxes is not None:
        return run_photo(args)

    ranges = ranges_from_args(args)
    data = plantation_dict(args.seed, ranges)
    if args.out:
        fileio.check_output_file(args.out, "--out")
        fileio.write_json(args.out, data)
        _, factors = generate(args.seed, ranges)
        print("%s: %s" % (args.out, ", ".join("%s %s" % kv for kv in factors.items())))
    else:
        print(json.dumps(data, indent=2))
    return 0


def run_photo(args: argparse.Namespace) -> int:
    """foranav plantation --photo: write a photo map and print what was found."""
    if args.photo is None or args.boxes is None:
        raise ForaNavError("--photo and --boxes: give both for a photo map")
    if not args.out:
        raise ForaNavError("--out: required with --photo (the map names its photo relative to itself)")
    fileio.check_output_file(args.out, "--out")
    request = PhotoMapRequest(args.photo, args.boxes, args.out, label=args.label, crown_m=_crown_m(args.crown_m),
                              gsd_m=args.gsd, altitude_m=1.25 if args.altitude is None else args.altitude,
                              heading_deg=args.heading, waypoints_px=_pixels(args.waypoints),
                              rows=_row_range(args.rows))
    result = build_photo_map(request)
    fileio.write_json(args.out, result.data)
    if result.fit is not None:
        print("%s: %d rows found (heading %.1f deg, row spacing %s m, palm spacing %.3f m), %d flown; %d of %d "
              "trees are targets; %.2f mm per photo pixel"
              % (args.out, result.rows_found, result.fit.heading_deg,
                 "%.3f" % result.row_spacing_m if result.row_spacing_m is not None else "-",
                 result.fit.palm_spacing, result.rows_flown, result.targets, result.trees,
                 result.metres_per_pixel * 1000))
    else:
        print("%s: %d waypoints given; %d of %d trees are targets; %.2f mm per photo pixel"
              % (args.out, len(result.data["waypoints"]), result.targets, result.trees, result.metres_per_pixel * 1000))
    return 0


def _crown_m(text: str | None) -> float | None:
    """--crown-m with --photo: one number of metres."""
    if text is None:
        return None
    try:
        return argtypes.positive(text)
    except argparse.ArgumentTypeError as err:
        raise ForaNavError("--crown-m: with --photo one crown size in metres: %s" % err)


def _pixels(texts: list[str] | None) -> tuple[tuple[float, float], ...] | None:
    if texts is None:
        return None
    points = []
    for text in texts:
        try:
            u, v = (float(p) for p in text.split(","))
        except ValueError:
            raise ForaNavError("--waypoints: expected U,V photo pixels, got %r" % text)
        if not (math.isfinite(u) and math.isfinite(v)):
            raise ForaNavError("--waypoints: must be finite, got %r" % text)
        points.append((u, v))
    if len(points) < 2:
        raise ForaNavError("--waypoints: needs at least 2 points, got %d" % len(points))
    return tuple(points)


def _row_range(text: str | None) -> tuple[int, int] | None:
    if text is None:
        return None
    try:
        parts = [int(p) for p in text.split(":")]
    except ValueError:
        raise ForaNavError("--rows: expected I:J or I (row numbers from 0), got %r" % text)
    if len(parts) not in (1, 2):
        raise ForaNavError("--rows: expected I:J or I, got %r" % text)
    return parts[0], parts[-1]
