"""Fly Map 1 with both halves over a real pseudo-terminal: the simulator renders each camera frame, the
unchanged JeVois module detects the oil palms and sends its serial lines into the pty, and the Crazyflie
navigation app reads them with pyserial on the emulated firmware and flies to every target tree.

Shows a progress bar while it flies, then a short summary table, and says where the trajectory plot and the
MAVLink telemetry log (open it in QGroundControl or MAVExplorer) were written (default runs/demo/).
With --crtp [HOST:]PORT the emulated Crazyflie also serves CRTP there for cflib and cfclient (docs/crtp.md).
"""
import argparse
import math
from typing import Any
import sys
import time
from pathlib import Path

from crazyflie_app.app.navigation_core import NavigationParams
from host_tools import argtypes, fileio
from host_tools.flight.cmd_fly import add_plant_argument, print_table
from host_tools.flight.components import check_crtp_endpoint, plant_config
from host_tools.flight.harness import run_flight
from host_tools.flight.vision_camera import VisionCamera, model_option
from host_tools.maps import PlantationMap, load_map
from host_tools.sim.cli_args import (add_appearance_arguments, appearance_from_args, photo_summary,
                                     refuse_appearance_on_photo_map)

DEMO_MAP = "map1"
DEMO_SEED = 0
BAR_WIDTH = 30
SECONDS_PER_TARGET = 7.0  # rough: approach, settle and return to the path (for the bar's estimate only)
TAKEOFF_AND_LANDING_S = 10.0


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--out", default="runs/demo", help="output folder (default runs/demo/)")
    parser.add_argument("--map", default=DEMO_MAP,
                        help="map file or built-in map (default %s; a photo map flies over its photo)" % DEMO_MAP)
    parser.add_argument("--seed", type=argtypes.seed, default=DEMO_SEED, help="seed of every random choice (default 0)")
    parser.add_argument("--model", metavar="M", default=None,
                        help="the module runs with this model file (.npz) (default: the oil palm model)")
    add_appearance_arguments(parser)
    add_plant_argument(parser)
    parser.add_argument("--crtp", type=argtypes.udp_endpoint, metavar="[HOST:]PORT", default=None,
                        help="serve CRTP on udp://HOST:PORT for cflib/cfclient (host 127.0.0.1 unless given; "
                             "docs/crtp.md)")


def estimated_mission_s(pmap: PlantationMap, cruise_speed: float) -> float:
    """A rough mission time for the progress bar: the path at cruise speed plus a few seconds per target."""
    length = sum(math.hypot(bx - ax, by - ay) for (ax, ay), (bx, by) in zip(pmap.waypoints, pmap.waypoints[1:]))
    return length / cruise_speed + SECONDS_PER_TARGET * len(pmap.targets) + TAKEOFF_AND_LANDING_S


def progress_line(t_s: float, phase: str, estimate_s: float, width: int = BAR_WIDTH) -> str:
    """'[#######-----------]  37%  t =  42 s  APPROACH' (capped at 99 % until the flight is over)."""
    fraction = min(0.99, max(0.0, t_s / estimate_s))
    filled = int(round(fraction * width))
    return "[%s%s] %3d%%  t = %4.0f s  %-14s" % ("#" * filled, "-" * (width - filled), 100 * fraction, t_s, phase)


class _Bar:
    def __init__(self, estimate_s, stream):
        self.estimate_s, self.stream = estimate_s, stream
        self.interactive = stream.isatty()
        self._last_decile = -1

    def __call__(self, t_s, phase):
        line = progress_line(t_s, phase, self.estimate_s)
        if self.interactive:
            self.stream.write("\r  " + line)
            self.stream.flush()
        else:  # a log file: one line per tenth
            decile = int(10 * min(0.99, t_s / self.estimate_s))
            if decile != self._last_decile:
                self._last_decile = decile
                self.stream.write("  " + line.rstrip() + "\n")

    def finish(self, t_s):
        line = "[%s] 100%%  t = %4.0f s  %-14s" % ("#" * BAR_WIDTH, t_s, "DONE")
        self.stream.write(("\r  " if self.interactive else "  ") + line + "\n")
        self.stream.flush()


def fly_demo(seed: int = DEMO_SEED, camera: VisionCamera | None = None, pmap: PlantationMap | None = None,
             **run_kwargs: Any) -> dict:
    """The demo's flight (Map 1 unless ``pmap``, the vision camera, the default options unless given): its
    summary. README's demo output is generated from it (``make docs``)."""
    pmap = pmap if pmap is not None else load_map(DEMO_MAP)
    camera = camera if camera is not None else VisionCamera(pmap, seed=seed)
    return run_flight(pmap, camera, seed=seed, **run_kwargs)


def run(args: argparse.Namespace) -> int:
    out = fileio.check_output_dir(Path(args.out))
    plant_config(args.plant, None)  # the firmware plant is built, or one line saying how
    if args.crtp:
        check_crtp_endpoint(args.crtp)
    pmap = load_map(args.map)
    spec, _ = appearance_from_args(args, {t.species for t in pmap.trees}, "map %s" % args.map)
    refuse_appearance_on_photo_map(spec, pmap, args.map)
    model = model_option(args.model) if args.model is not None else None
    print("ForaNav demo: %s" % pmap.name)
    print("  camera: simulator -> JeVois module (ForaNavTrees, unchanged) -> pty -> Crazyflie app (pyserial)")
    started = time.monotonic()
    camera = VisionCamera(pmap, seed=args.seed, appearance=None if spec.default else spec, model=model)
    if photo_summary(camera.world):
        print("  " + photo_summary(camera.world))
    if args.crtp:
        print("  CRTP: the Crazyflie answers on udp://%s (cflib, cfclient)" % args.crtp)
    bar = _Bar(estimated_mission_s(pmap, NavigationParams().cruise_speed), sys.stdout)
    options = {"plant": args.plant}
    if args.crtp:
        options["crtp"] = args.crtp
    summary = fly_demo(args.seed, camera, pmap, out_dir=out, progress=bar, options=options)
    bar.finish(summary["mission_time_s"])
    summary.pop("cpu_s", None)
    print()
    print_table(summary)
    print("  detections csv %s\n  summary %s" % (summary["detections_csv"], summary["summary"]))
    print("  wall time %.1f s" % (time.monotonic() - started))
    print("Open the plot to see the flown trajectory over the map; replay the telemetry with MAVExplorer or "
          "QGroundControl (File > Open telemetry log).")
    return 0 if summary["completed"] else 1
