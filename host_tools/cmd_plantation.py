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

Examples:
  foranav plantation --seed 7 --out runs/p7.json
  foranav plantation --seed 7 --columns 3 --altitude-m 1.0 --off-column-palms 2 --out p.json
  foranav plantation --seed 7 --profile classic --out p.json      # the map seed 7 gave before
  foranav fly --map runs/p7.json --camera oracle
"""
import argparse
import dataclasses
import json
import re

from host_tools import argtypes, fileio
from host_tools.errors import ForaNavError
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
    parser.add_argument("--out", help="write the map here (default: print it)")
    add_range_arguments(parser)


def run(args: argparse.Namespace) -> int:

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
