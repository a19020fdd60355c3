"""Benchmarks that print figures: foranav bench {sim,detector,flight,sweep,recall,crtp} [--json].

sim:      rendered 352x288 camera frames per second on one core (plantation simulator); with --crowns CSV ...
          also over photo crowns, next to the procedural figures.
flight:   simulated seconds per CPU second of an oracle flight (firmware emulation + app); --plant firmware
          adds the firmware plant's flights beside the reduced plant's; --camera sim: CPU of a vision flight
          against an oracle flight of the same map, user vs system, and the vision flight's CPU by stage.
detector: ms per frame and FPS of the tree detector at 352x288, 640x480 and 1280x1024, peak memory, and the
          speed-up over the per-window reference implementation.
sweep:    flights per CPU-second and the 1 -> 2 Dask worker speed-up (--camera sim|oracle, --count N).
recall:   how often the camera module sees the crown under the MAV from straight above: isolated, touching
          one or two neighbours, small beside a larger one, centred and off-centre (--model, --count frames
          per case, --seed, --grouping nms|period, --period auto|map).
crtp:     datagrams per second the CRTP server handles (dispatch alone, and over UDP from another process),
          and the CPU and wall seconds of the Map 1 oracle flight without --crtp, with it, and with stock cflib
          streaming a 100 Hz log block.
"""
import argparse
import importlib

from host_tools import argtypes
from host_tools.errors import ForaNavError
from crazyflie_app.firmware.system import PLANTS
from host_tools.sim.cli_args import add_appearance_arguments
from jevois_module.ForaNavTrees.foranav_detector import GROUPINGS

TARGETS = {
    "sim": "host_tools.sim.bench",
    "detector": "host_tools.detection.bench",
    "flight": "host_tools.flight.bench",
    "sweep": "host_tools.sweep.bench",
    "recall": "host_tools.detection.recall_bench",
    "crtp": "host_tools.flight.crtp_bench",
}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("target", choices=sorted(TARGETS), help="what to benchmark")
    parser.add_argument("--json", action="store_true", help="print one JSON object instead of a table")
    parser.add_argument("--seed", type=argtypes.seed, default=0, help="seed of the rendered test frames")
    parser.add_argument("--camera", choices=("sim", "oracle"), default=None,
                        help="sweep: camera (default sim); flight: sim compares vision and oracle flights")
    parser.add_argument("--count", type=argtypes.int_range(1, 100000), default=None,
                        help="sweep: flights per worker count (default 6); recall: frames per case (default 150)")
    parser.add_argument("--model", default=None,
                        help="detector, recall: model file, or a shipped species (default: the shipped oil palm model)")
    parser.add_argument("--grouping", choices=GROUPINGS, default=None,
                        help="recall and detector: the detector's grouping of peaks into trees (default nms, "
                        "today's; period: the period-tied peak stage)")
    parser.add_argument("--period", choices=("auto", "map"), default=None,
                        help="recall with --grouping period: the period from each frame (auto, default) or the "
                        "scene's neighbour spacing in pixels sent to the module (map)")
    add_appearance_arguments(parser)  # bench sim and recall: --crowns / --ground
    parser.add_argument("--plant", choices=PLANTS, default=None,
                        help="flight: also fly the firmware plant (beside the reduced plant)")


MODEL_TARGETS = ("detector", "recall")  # the targets that run a model of the user's choice


def run(args: argparse.Namespace) -> int:
    if args.model is not None and args.target not in MODEL_TARGETS:
        raise ForaNavError("--model: only with bench %s (bench %s runs no detector model of yours)"
                           % (" or ".join(MODEL_TARGETS), args.target))
    return importlib.import_module(TARGETS[args.target]).run(args)
