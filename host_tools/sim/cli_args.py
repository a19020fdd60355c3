"""Argument helpers shared by the simulator's commands."""
import argparse
import math
from collections.abc import Iterable
from pathlib import Path

from host_tools import argtypes
from host_tools.errors import ForaNavError
from host_tools.maps import PlantationMap
from host_tools.sim.camera import HEIGHT_RANGE_M, MOUNT_OFFSET_RANGE_M, CameraModel, SENSOR_MODES
from host_tools.sim.crowns import Appearance, AppearanceSpec, load_appearance
from host_tools.sim.world import NO_EFFECTS, SENSOR_EFFECTS, World

EFFECT_PRESETS = {"none": NO_EFFECTS, "sensor": SENSOR_EFFECTS}
MOUNT_OFFSET_M = argtypes.float_range(*MOUNT_OFFSET_RANGE_M)
ALTITUDE_M = argtypes.float_range(*HEIGHT_RANGE_M)


def add_camera_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--width", type=int, default=352, help="sensor mode width (default 352)")
    parser.add_argument("--height", type=int, default=288, help="sensor mode height (default 288)")
    parser.add_argument("--mount-offset", type=MOUNT_OFFSET_M, nargs=2, default=(0.0, 0.0), metavar=("FWD", "LEFT"),
                        action=argtypes.Once,
                        help="camera position relative to the MAV, body frame metres (default 0 0)")
    parser.add_argument("--effects", choices=sorted(EFFECT_PRESETS), default="none",
                        help="per-frame camera effects: none (default) or sensor (blur, noise, JPEG)")


def camera_from_args(args: argparse.Namespace) -> CameraModel:
    if (args.width, args.height) not in SENSOR_MODES:
        raise ForaNavError("--width/--height: unknown sensor mode %dx%d (expected one of %s)"
                           % (args.width, args.height, ", ".join("%dx%d" % m for m in SENSOR_MODES)))
    return CameraModel(args.width, args.height, tuple(args.mount_offset))


def add_appearance_arguments(parser: argparse.ArgumentParser) -> None:
    """--crowns / --ground / --ground-gsd / --crown-shadows: how the world looks (one parser, every command)."""
    group = parser.add_argument_group("appearance (photo crowns and ground; see docs/simulator.md)")
    group.add_argument("--crowns", nargs="+", action="extend", default=None, metavar="CSV",
                       help="draw trees from the boxes of these annotation CSVs (the crown library, by label: "
                            "oil_palm, coconut, olive_tree->olive, date_palm, citrus); other species as drawn")
    group.add_argument("--ground", metavar="IMAGE", default=None,
                       help="a photo of bare ground or grass, tiled, instead of the procedural ground")
    group.add_argument("--ground-gsd", type=argtypes.positive, default=None, metavar="M_PER_PX",
                       help="ground sampling distance of --ground, metres per pixel (required with --ground)")
    group.add_argument("--crown-shadows", action="store_true",
                       help="photo crowns also cast the drawn shadow (default: the photo's own shading only)")


def appearance_spec_from_args(args: argparse.Namespace) -> AppearanceSpec:
    """The AppearanceSpec of the parsed options (paths resolved), checked for consistency (not loaded)."""
    crowns = tuple(str(Path(p).resolve()) for p in (getattr(args, "crowns", None) or ()))
    ground = getattr(args, "ground", None)
    gsd = getattr(args, "ground_gsd", None)
    if ground is not None:
        if gsd is None:
            raise ForaNavError("--ground %s: needs --ground-gsd (metres per pixel of the photo)" % ground)
        if not (math.isfinite(gsd) and gsd > 0):
            raise ForaNavError("--ground-gsd: must be a positive number, got %r" % gsd)
        ground = str(Path(ground).resolve())
    elif gsd is not None:
        raise ForaNavError("--ground-gsd: only with --ground IMAGE")
    return AppearanceSpec(crowns, ground, gsd, bool(getattr(args, "crown_shadows", False)))


def appearance_from_args(args: argparse.Namespace, species: Iterable[str],
                         what: str) -> tuple[AppearanceSpec, Appearance | None]:
    """(AppearanceSpec, loaded Appearance or None), checked against the ``species`` that ``what`` draws.

    Raises ForaNavError (one line naming the file and row) before the command writes anything."""
    spec = appearance_spec_from_args(args)
    appearance = load_appearance(spec)
    if appearance is not None:
        appearance.check_species(species, what)
    return spec, appearance


def refuse_appearance_on_photo_map(spec: AppearanceSpec, pmap: PlantationMap, map_name: str) -> None:
    """--crowns/--ground draw trees and ground; a photo map's world is its photo: ForaNavError when both."""
    if pmap.photo is not None and not spec.default:
        raise ForaNavError("--crowns/--ground: map %s is a photo map (its world is its photo; nothing is drawn)"
                           % map_name)


def photo_summary(world: World) -> str | None:
    """One line: which species of the world came from photos (or None without photo crowns)."""
    if not world.photo_crowns:
        return None
    drawn = sorted({t.species for t in world.map.trees} - set(world.photo_species))
    return "crowns from photos: %s (%d trees)%s" % (", ".join(world.photo_species), len(world.photo_crowns),
                                                   "; drawn: %s" % ", ".join(drawn) if drawn else "")
