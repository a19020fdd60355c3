"""Run the tree detector on images: one line per image (one JSON object with --json).

Example: foranav detect frame.png --json
JSON: {"image", "width", "height", "detections": [{"x", "y", "w", "h", "score"}]} (pixels; x, y = centre),
detections best first. --window PX replaces the model's window sizes by one size in pixels of the image.
"""
import json
import sys

from host_tools.detection import common, dataset
from host_tools.detection.threads import single_threaded
from host_tools.errors import ForaNavError

import foranav_detector as detector_core


def add_arguments(parser):
    parser.add_argument("images", nargs="+", metavar="IMAGE", help="image files (any format OpenCV reads)")
    parser.add_argument("--model", default="oil_palm",
                        help="model file, or a shipped species: oil_palm (default), citrus, olive")
    parser.add_argument("--window", type=float, action="append", metavar="PX",
                        help="window side in pixels (repeat for several; default: the model's sizes)")
    parser.add_argument("--step", type=int, default=detector_core.DEFAULT_STEP,
                        help="window step in downscaled pixels, 1..24 (default %d = W/12; paper: 8 = W/3)"
                        % detector_core.DEFAULT_STEP)
    parser.add_argument("--json", action="store_true", help="one JSON object per image")


def run(args):
    single_threaded()
    model = common.load(args.model)
    if args.window and min(args.window) < 24:
        raise ForaNavError("--window must be at least 24 px")
    try:
        settings = detector_core.DetectorSettings(window_sizes=args.window, step=args.step)
    except ValueError as err:
        raise ForaNavError(str(err))
    detector = detector_core.TreeDetector(model, settings)
    images = [(path, dataset.read_image(path)) for path in args.images]  # all readable before any output
    for path, bgr in images:
        height, width = bgr.shape[:2]
        if args.window and max(args.window) > min(width, height):
            raise ForaNavError("%s: window %g px is larger than the %dx%d frame" % (path, max(args.window), width,
                                                                                   height))
        try:
            detections = detector.detect(bgr)
        except ValueError as err:
            raise ForaNavError("%s: %s" % (path, err))
        if args.json:
            print(json.dumps({"image": path, "width": width, "height": height, "detections": [
                {"x": round(d.x, 2), "y": round(d.y, 2), "w": round(d.w, 2), "h": round(d.h, 2),
                 "score": round(d.score, 4)} for d in detections]}))
        else:
            found = ", ".join("(%.1f, %.1f) %.0fpx %.2f" % (d.x, d.y, d.w, d.score) for d in detections)
            print("%s: %d tree%s %s" % (path, len(detections), "" if len(detections) == 1 else "s", found))
        sys.stdout.flush()
    return 0
