"""Fly the map's path F at constant speed and altitude and write a clip (MJPG AVI + JSON sidecar).

Example: foranav record --map map1 --out clips/map1 --speed 0.3 --fps 10
The MAV holds yaw (default 0, as the paper's navigation app does) and altitude (default: the map's).
The sidecar format is documented in host_tools/sim/clip.py and README.md (Clips).
"""
import argparse

import numpy as np

from host_tools import argtypes, fileio
from host_tools.errors import ForaNavError
from host_tools.maps import load_map, map_to_dict
from host_tools.sim.cli_args import (ALTITUDE_M, EFFECT_PRESETS, add_appearance_arguments, add_camera_arguments,
                                     appearance_from_args, camera_from_args, photo_summary,
                                     refuse_appearance_on_photo_map)
from host_tools.sim.clip import DEFAULT_QUALITY, write_clip
from host_tools.sim.path import path_length, poses_along_path
from host_tools.sim.world import World

MAX_FPS = 120.0  # the fastest JeVois-A33 sensor mode
MAX_FRAMES = 50000  # 1.5 hours at 9 fps: a longer clip is a typo (--speed 0.0001), not a recording


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--map", required=True, help="map file or built-in map name (map1, map2, map3)")
    parser.add_argument("--out", required=True, help="output folder (clip.avi + clip.json)")
    parser.add_argument("--speed", type=argtypes.float_range(0.01, 10.0), default=0.3,
                        help="ground speed, m/s, 0.01-10 (default 0.3)")
    parser.add_argument("--fps", type=argtypes.float_range(0.1, MAX_FPS), default=10.0,
                        help="frames per second, 0.1-%g (default 10)" % MAX_FPS)
    parser.add_argument("--seed", type=argtypes.seed, default=None, help="world seed (default: the map's seed)")
    parser.add_argument("--z", type=ALTITUDE_M, default=None, help="altitude, metres (default: the map's)")
    parser.add_argument("--yaw", type=argtypes.finite, default=0.0, help="held yaw, degrees (default 0)")
    parser.add_argument("--start", type=argtypes.nonnegative, default=0.0,
                        help="start this many metres along the path")
    parser.add_argument("--duration", type=argtypes.positive, default=None, help="stop after this many seconds")
    parser.add_argument("--quality", type=argtypes.int_range(1, 100), default=DEFAULT_QUALITY,
                        help="MJPG quality 1-100 (default 75)")
    add_camera_arguments(parser)
    add_appearance_arguments(parser)


def run(args: argparse.Namespace) -> int:
    fileio.check_output_dir(args.out)
    pmap = load_map(args.map)
    camera = camera_from_args(args)
    z = args.z if args.z is not None else pmap.altitude_m
    length = path_length(pmap.waypoints)
    if not 0.0 <= args.start < length:
        raise ForaNavError("--start: must be within the path (0 to %.2f m)" % length)
    seconds = (length - args.start) / args.speed
    if args.duration is not None:
        seconds = min(seconds, args.duration)
    if seconds * args.fps > MAX_FRAMES:
        raise ForaNavError("--fps/--speed/--duration: %.0f frames, more than %d (a slower --fps, a faster --speed "
                           "or a --duration)" % (seconds * args.fps, MAX_FRAMES))
    spec, appearance = appearance_from_args(args, {t.species for t in pmap.trees}, "map %s" % args.map)
    refuse_appearance_on_photo_map(spec, pmap, args.map)
    world = World.from_map(pmap, seed=args.seed, appearance=appearance)
    timed = poses_along_path(pmap.waypoints, args.speed, args.fps, z, args.yaw, args.duration, args.start)
    effects = EFFECT_PRESETS[args.effects]
    rng = np.random.default_rng(world.seed)
    frames = (world.render(camera, pose, rng=rng, effects=effects) for _, pose in timed)
    source = {"command": "record", "map": args.map, "seed": world.seed, "speed_m_s": args.speed,
              "z_m": z, "yaw_deg": args.yaw, "start_m": args.start, "duration_s": args.duration,
              "quality": args.quality, "effects": args.effects}
    if not spec.default:  # only then: a default clip's sidecar keeps its bytes
        source["appearance"] = spec.to_dict()
        source["photo_species"] = list(world.photo_species)
    try:
        count = write_clip(args.out, frames, [t for t, _ in timed], camera, args.fps, map_to_dict(pmap), source,
                           args.quality)
    except OSError as err:
        raise ForaNavError("%s: cannot write the clip: %s" % (args.out, err.strerror or err))
    print("wrote %s: %d frames, %.1f s at %.2f m/s, %dx%d" % (args.out, count, timed[-1][0], args.speed,
                                                              camera.width, camera.height))
    if photo_summary(world):
        print(photo_summary(world))
    return 0
