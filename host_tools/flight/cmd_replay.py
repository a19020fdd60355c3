"""Replay a recorded clip (video + pose sidecar) through both halves, open loop.

The clip's frames go through the unchanged JeVois module and over a real pseudo-terminal into the Crazyflie
app, whose state estimate follows the recorded poses (whatever it commands). Reports the detections per frame
against the sidecar's ground truth, the tree map the app built (world positions against the map) and the
setpoints the app would have sent. A video that is not the one the sidecar was recorded with (its SHA-256
differs: another clip's, another map's) is refused; a --map other than the map the clip was recorded over is
replayed with a warning. The sidecar format (also for real footage with a pose log) is documented in
host_tools/sim/clip.py and README.md (Clips).

Examples:
  foranav replay tests/fixtures/clips/map1_full
  foranav replay my_clip/ --map map2 --json
"""
import argparse
import json
import sys
from typing import TextIO

from host_tools import argtypes
from host_tools.errors import ForaNavError
from host_tools.flight.replay import map_override_warning, replay_clip
from host_tools.maps import load_map
from host_tools.flight.registry import FPS_RANGE
from host_tools.sim.clip import read_clip

LATENCY_MAX_MS = 5000  # as fly --latency-ms


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("clip", help="clip folder (clip.avi + clip.json) or its clip.json")
    parser.add_argument("--map", help="map giving the path F, when the sidecar has none (or to override it: a map "
                        "other than the recorded one is warned about)")
    parser.add_argument("--latency-ms", type=argtypes.int_range(0, LATENCY_MAX_MS), default=None,
                        help="delay of the module's lines on the wire (default: one clip frame)")
    parser.add_argument("--json", action="store_true", help="print the full report (with per-frame rows and "
                        "setpoints) as one JSON object")
    parser.add_argument("--app", choices=("python", "c"), default="python",
                        help="flight app: python (default) or c (the C core of crazyflie_app/bolt)")


def print_report(report: dict, out: TextIO | None = None) -> None:
    out = out or sys.stdout
    det = report["detection"]
    print("replay %s: %d frames, %.1f s, latency %d ms" % (report["clip"], report["frames"], report["duration_s"],
                                                         report["latency_ms"]), file=out)
    if det:
        print("  detections: %.2f per frame; %d true, %d false, %d missed (recall %s, precision %s); mean pixel "
              "error %s px" % (det["detections_per_frame"] or 0.0, det["true_positives"], det["false_positives"],
                               det["missed"], det["recall"], det["precision"], det["mean_pixel_error"]), file=out)
    else:
        print("  detections: no ground truth in the sidecar", file=out)
    print("  tree map (app) vs truth:", file=out)
    print("    %-6s %-16s %-8s %s" % ("app", "position (m)", "map id", "error (m)"), file=out)
    for t in report["tree_map"]:
        print("    %-6d (%6.3f, %6.3f)  %-8s %s" % (t["app_id"], t["x"], t["y"], t["map_id"] or "-",
                                                  "-" if t["error_m"] is None else "%.3f" % t["error_m"]), file=out)
    print("  mean map error %s m, max %s m; trees seen whole but not mapped: %s; spurious app trees: %d" % (
        report["tree_map_mean_error_m"], report["tree_map_max_error_m"], report["trees_seen_not_mapped"] or "none",
        report["spurious_app_trees"]), file=out)
    sp = report["setpoints"]
    print("  setpoints: %d sampled; time per phase %s" % (len(sp), report["phases"]), file=out)
    for row in sp[:: max(1, len(sp) // 8)]:
        print("    t %5.1f s  %-14s v (%.2f, %.2f) m/s  z %.2f m" % (row["t_s"], row["phase"], row["vx"], row["vy"],
                                                                 row["z"]), file=out)


def run(args: argparse.Namespace) -> int:
    clip = read_clip(args.clip)
    if not FPS_RANGE[0] <= clip.fps <= FPS_RANGE[1]:
        raise ForaNavError("%s: fps: a clip at %g fps; the app flies on %g to %g frames per second (its camera "
                           "link watch is 1 s)" % ((clip.directory / "clip.json", clip.fps) + FPS_RANGE))
    clip.check_video()
    pmap = load_map(args.map) if args.map else None
    warning = map_override_warning(clip, pmap) if pmap is not None else None
    if warning:
        print("warning: " + warning, file=sys.stderr)
    if args.latency_ms is not None and args.latency_ms < 0:
        raise ForaNavError("--latency-ms: must not be negative")
    report = replay_clip(clip, pmap, latency_ms=args.latency_ms, app=args.app)
    if args.json:
        print(json.dumps(report, indent=2))
    else:
        print_report(report)
    return 0
