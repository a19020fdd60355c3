"""Render one downward camera view of a map to a PNG.

Example: foranav render --map map1 --x 1.86 --y 0.57 --out frame.png
The altitude defaults to the map's flight height; --seed overrides the map's seed (ground and tree variation).
Prints the trees in view (id, species, target, pixel centre and box size, complete or cut by the frame edge).
"""
import argparse

import cv2
import numpy as np

from host_tools import argtypes, fileio
from host_tools.errors import ForaNavError
from host_tools.maps import load_map
from host_tools.sim.camera import Pose
from host_tools.sim.cli_args import (ALTITUDE_M, EFFECT_PRESETS, add_appearance_arguments, add_camera_arguments,
                                     appearance_from_args, camera_from_args, photo_summary,
                                     refuse_appearance_on_photo_map)
from host_tools.sim.world import World


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--map", required=True, help="map file or built-in map name (map1, map2, map3)")
    parser.add_argument("--x", type=argtypes.finite, required=True, help="MAV x, metres (forward along the rows)")
    parser.add_argument("--y", type=argtypes.finite, required=True, help="MAV y, metres (left)")
    parser.add_argument("--z", type=ALTITUDE_M, default=None, help="height, metres (default: the map's altitude)")
    parser.add_argument("--yaw", type=argtypes.finite, default=0.0, help="yaw, degrees counter-clockwise (default 0)")
    parser.add_argument("--seed", type=argtypes.seed, default=None, help="world seed (default: the map's seed)")
    add_camera_arguments(parser)
    add_appearance_arguments(parser)
    parser.add_argument("--out", required=True, help="output PNG")


def run(args: argparse.Namespace) -> int:
    fileio.check_output_file(args.out)
    pmap = load_map(args.map)
    camera = camera_from_args(args)
    z = args.z if args.z is not None else pmap.altitude_m
    spec, appearance = appearance_from_args(args, {t.species for t in pmap.trees}, "map %s" % args.map)
    refuse_appearance_on_photo_map(spec, pmap, args.map)
    world = World.from_map(pmap, seed=args.seed, appearance=appearance)
    frame = world.render(camera, Pose(args.x, args.y, z, args.yaw), effects=EFFECT_PRESETS[args.effects])
    write_png(args.out, frame.image)
    for t in frame.trees:
        print("tree %d %s target=%s u=%.1f v=%.1f w=%.1f h=%.1f %s"
              % (t.id, t.species, str(t.target).lower(), t.u, t.v, t.w, t.h,
                 "complete" if t.complete else "partial"))
    if photo_summary(world):
        print(photo_summary(world))
    return 0


def write_png(path: str, image: np.ndarray) -> None:
    """Write a PNG atomically; fixed compression so the same image gives the same bytes."""
    ok, data = cv2.imencode(".png", image, [cv2.IMWRITE_PNG_COMPRESSION, 6])
    if not ok:
        raise ForaNavError("%s: cannot encode PNG" % path)
    try:
        fileio.write_bytes(path, data.tobytes())
    except OSError as err:
        raise ForaNavError("%s: cannot write: %s" % (path, err.strerror or err))
