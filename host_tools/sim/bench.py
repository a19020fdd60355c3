"""Simulator benchmark: rendered 352x288 camera frames per second on one core.

The orthomosaic of Map 1 is rendered once (timed separately); then frames are rendered at random poses over
the path at varied yaw, without and with per-frame sensor effects, and in every sensor mode. With --crowns
CSV ... (and --ground), the same again over a Map 1 drawn with photo crowns, reported next to the procedural
figures (loading the library, the photo mosaic build and its frames/s).
"""
import argparse
import json
import time
from collections.abc import Callable, Sequence

import cv2
import numpy as np

from host_tools.maps import PlantationMap, load_map
from host_tools.sim.camera import SENSOR_MODES, CameraModel, Pose
from host_tools.sim.cli_args import appearance_from_args
from host_tools.sim.world import SENSOR_EFFECTS, Effects, World

TARGET_FPS = 500
MIN_SECONDS = 1.0


def measure(world: World, camera: CameraModel, poses: Sequence[Pose], effects: Effects | None = None,
            min_seconds: float = MIN_SECONDS, clock: Callable[[], float] = time.perf_counter) -> float:
    """Frames per second rendering the poses round-robin for at least min_seconds."""
    rng = np.random.default_rng(0)
    count, start = 0, clock()
    while True:
        for pose in poses:
            if effects is None:
                world.render(camera, pose)
            else:
                world.render(camera, pose, rng=rng, effects=effects)
        count += len(poses)
        elapsed = clock() - start
        if elapsed >= min_seconds:
            return count / elapsed


def flight_poses(pmap: PlantationMap, count: int = 200, seed: int = 0) -> list[Pose]:
    rng = np.random.default_rng(seed)
    xs = rng.uniform(0.3, 3.9, count)
    ys = rng.uniform(-0.6, 0.6, count)
    yaws = rng.uniform(-180, 180, count)
    return [Pose(float(x), float(y), pmap.altitude_m, float(a)) for x, y, a in zip(xs, ys, yaws)]


def run(args: argparse.Namespace) -> int:
    cv2.setNumThreads(1)
    pmap = load_map("map1")
    start = time.perf_counter()
    world = World.from_map(pmap, seed=getattr(args, "seed", None))
    build_s = time.perf_counter() - start
    camera = CameraModel()
    poses = flight_poses(pmap, seed=getattr(args, "seed", 0) or 0)
    world.render(camera, poses[0])  # warm-up
    result = {
        "frame": "352x288",
        "threads": 1,
        "mosaic_build_s": round(build_s, 3),
        "mosaic_px": list(world.levels[0].shape[:2]),
        "fps": round(measure(world, camera, poses), 1),
        "fps_sensor_effects": round(measure(world, camera, poses, SENSOR_EFFECTS), 1),
        "target_fps": TARGET_FPS,
    }
    result["meets_target"] = result["fps"] >= TARGET_FPS
    result["fps_by_mode"] = {"%dx%d" % mode: round(measure(world, CameraModel(*mode), poses, min_seconds=0.3), 1)
                             for mode in SENSOR_MODES}
    photo = _photo_figures(args, pmap, camera, poses)
    if photo:
        result["photo_crowns"] = photo
    if getattr(args, "json", False):
        print(json.dumps(result))
    else:
        print("simulator: 352x288 camera frames on one core (map1)")
        print("  orthomosaic build       %8.3f s  (%d x %d px)" % (build_s, *world.levels[0].shape[1::-1]))
        print("  frames/s (no effects)   %8.1f    target >= %d: %s"
              % (result["fps"], TARGET_FPS, "met" if result["meets_target"] else "NOT met"))
        print("  frames/s (sensor fx)    %8.1f    (blur, noise, JPEG round trip)" % result["fps_sensor_effects"])
        for mode, fps in result["fps_by_mode"].items():
            print("  frames/s %-10s      %8.1f    (no effects)" % (mode, fps))
        if photo:
            print("  photo crowns (%s from photos; library of %d crowns loaded in %.3f s)"
                  % (", ".join(photo["species"]), photo["library_crowns"], photo["library_load_s"]))
            print("  orthomosaic build       %8.3f s  (procedural %.3f s)" % (photo["mosaic_build_s"], build_s))
            print("  frames/s (no effects)   %8.1f    (procedural %.1f)" % (photo["fps"], result["fps"]))
            print("  frames/s (sensor fx)    %8.1f    (procedural %.1f)"
                  % (photo["fps_sensor_effects"], result["fps_sensor_effects"]))
    return 0


def _photo_figures(args, pmap, camera, poses):
    """The same figures over a world drawn with --crowns / --ground, or None without them."""
    if not getattr(args, "crowns", None) and getattr(args, "ground", None) is None:
        return None
    start = time.perf_counter()
    _, appearance = appearance_from_args(args, {t.species for t in pmap.trees}, "map map1")
    load_s = time.perf_counter() - start
    start = time.perf_counter()
    world = World.from_map(pmap, seed=getattr(args, "seed", None), appearance=appearance)
    build_s = time.perf_counter() - start
    world.render(camera, poses[0])  # warm-up
    library = appearance.library
    return {"species": list(world.photo_species),
            "library_crowns": sum(library.count(s) for s in library.species) if library else 0,
            "library_load_s": round(load_s, 3), "mosaic_build_s": round(build_s, 3),
            "fps": round(measure(world, camera, poses), 1),
            "fps_sensor_effects": round(measure(world, camera, poses, SENSOR_EFFECTS), 1)}
