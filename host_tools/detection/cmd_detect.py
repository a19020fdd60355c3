"""Run the tree detector on images: one line per image (one JSON object with --json).

Example: foranav detect survey.png --crown-px 160 --json
JSON: {"image", "width", "height", "domain", "windows", "detections": [{"x", "y", "w", "h", "score"}]}
(pixels; x, y = centre), detections best first, every tree found (--max-detections N caps).
Scale: give the typical crown diameter in the image, --crown-px N or --gsd M_PER_PX --crown-m M; the windows
are that times the model's calibrated window/crown ratios. Without it the model's window sizes scale with
the frame width (right for flight-camera frames only: a warning says so for other images). --window PX
gives the window sizes directly. --domain NAME picks the model's imagery (colour model and thresholds);
default: the only one, or the one whose colours are nearest each image's.
"""
import argparse
import json
import math
import sys

from host_tools import argtypes
from host_tools.detection import common, dataset
from host_tools.threads import single_threaded
from host_tools.errors import ForaNavError

import foranav_detector as detector_core
import foranav_model

# Frame sizes of the JeVois sensor modes: there the model's windows scale with the width as the lens does.
CAMERA_SIZES = {(88, 72), (160, 120), (176, 144), (320, 240), (352, 288), (640, 480), (1280, 1024)}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("images", nargs="+", metavar="IMAGE", help="image files (any format OpenCV reads)")
    parser.add_argument("--model", default="oil_palm",
                        help="model file, or a shipped species: oil_palm (default), citrus, olive")
    parser.add_argument("--crown-px", type=float, metavar="N", help="typical crown diameter in the images, pixels")
    parser.add_argument("--gsd", type=float, metavar="M_PER_PX", help="ground sampling distance, metres per pixel "
                        "(with --crown-m)")
    parser.add_argument("--crown-m", type=float, metavar="M", help="typical crown diameter, metres (with --gsd)")
    parser.add_argument("--window", type=float, action="append", metavar="PX",
                        help="window side in pixels (repeat for several; default: from the crown size)")
    parser.add_argument("--max-detections", type=argtypes.int_range(*common.MAX_DETECTIONS_RANGE), metavar="N", help="report at most N trees per image, best "
                        "first (default: all)")
    parser.add_argument("--domain", metavar="NAME", help="the model's imagery to use (default: the nearest in colour)")
    parser.add_argument("--step", type=argtypes.int_range(*common.STEP_RANGE), default=detector_core.DEFAULT_STEP,
                        help="window step in downscaled pixels, 1..24 (default %d = W/12; paper: 8 = W/3)"
                        % detector_core.DEFAULT_STEP)
    parser.add_argument("--json", action="store_true", help="one JSON object per image")


def settings_for(args: argparse.Namespace, model: foranav_model.TreeModel, crown_px: float | None) -> dict:
    if args.window and crown_px is not None:
        raise ForaNavError("give --window or a crown size (--crown-px, --gsd/--crown-m), not both")
    if args.window and not all(math.isfinite(w) and w >= 24 for w in args.window):
        raise ForaNavError("--window must be at least 24 px")
    if args.max_detections is not None and args.max_detections < 1:
        raise ForaNavError("--max-detections must be at least 1")
    if args.domain is not None:
        try:
            model.domain(args.domain)
        except foranav_model.ModelFormatError as err:
            raise ForaNavError("--domain: %s" % err)
    windows = args.window or (detector_core.crown_window_sizes(model, crown_px) if crown_px else None)
    try:
        return detector_core.DetectorSettings(window_sizes=windows, step=args.step,
                                              max_detections=args.max_detections, domain=args.domain)
    except ValueError as err:
        raise ForaNavError(str(err))


def run(args: argparse.Namespace) -> int:
    single_threaded()
    model = common.load(args.model)
    crown_px = common.crown_pixels(args)
    settings = settings_for(args, model, crown_px)
    detector = detector_core.TreeDetector(model, settings)
    images = [(path, dataset.read_frame(path)) for path in args.images]  # all readable before any output
    common.check_crown_fits(crown_px, [bgr.shape[1::-1] for _path, bgr in images], "the images")
    warned = set()
    for path, bgr in images:
        height, width = bgr.shape[:2]
        windows = detector.window_sizes(width)
        if max(windows) > min(width, height):
            raise ForaNavError("%s: window %g px is larger than the %dx%d frame (crown size or --window too large)"
                               % (path, max(windows), width, height))
        if settings.window_sizes is None and (width, height) not in CAMERA_SIZES and (width, height) not in warned:
            warned.add((width, height))
            print("detect: warning: %s is %dx%d, not a flight-camera frame, and no scale was given: windows %s px "
                  "follow the frame width; give --crown-px or --gsd with --crown-m"
                  % (path, width, height, ",".join("%g" % w for w in windows)), file=sys.stderr)
        try:
            detections = detector.detect(bgr)
        except ValueError as err:
            raise ForaNavError("%s: %s" % (path, err))
        domain = model.domains[detector.domain_index].name
        if args.json:
            print(json.dumps({"image": path, "width": width, "height": height, "domain": domain,
                              "windows": [round(w, 1) for w in windows], "detections": [
                                  {"x": round(d.x, 2), "y": round(d.y, 2), "w": round(d.w, 2), "h": round(d.h, 2),
                                   "score": round(d.score, 4)} for d in detections]}))
        else:
            found = ", ".join("(%.1f, %.1f) %.0fpx %.2f" % (d.x, d.y, d.w, d.score) for d in detections)
            print("%s: %d tree%s %s" % (path, len(detections), "" if len(detections) == 1 else "s", found))
        sys.stdout.flush()
    return 0
