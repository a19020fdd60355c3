"""foranav bench detector: speed of the tree detector on one core.

For 352x288, 640x480 and 1280x1024 frames (synthetic palm scenes, crowns scaled with the frame width as
the camera's lens does): median and p90 milliseconds per frame and frames per second of the fast path
(whole detect(): HSV, score maps, candidates, per-object tests, NMS), the per-window reference
implementation of the same pipeline timed on the same frame(s), their ratio, and the peak resident memory.
The process is pinned to one CPU and OpenCV/BLAS are limited to one thread. Then the estimated JeVois-A33 rate:
the median CPU time per frame times A33_FACTOR (docs/hardware.md), for the shipped flight model and for the
shipped model with a network (foranav_oil_palm_cnn.npz) at 352x288. ``--grouping period``: the same with the
period-tied peak stage on (the period estimated from each frame).
"""
import argparse
import json
import os
import resource
import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from host_tools.detection import common, reference, synthetic
from host_tools.threads import single_threaded
from host_tools.jevois_host import DEFAULT_MODULE_DIR

import foranav_detector as detector_core

SIZES = ((352, 288), (640, 480), (1280, 1024))
FAST_FRAMES = {352: 200, 640: 100, 1280: 40}  # timed frames per size (after warm-up)
REFERENCE_FRAMES = 1  # the per-window path takes about a second per frame
CROWNS_AT_352 = (77, 115)  # crown diameters in pixels at 352 px width and 1.25 m altitude
# A33 time / this host's CPU time, measured by `python -m host_tools.detection.a33_factor` (MobileNet v1 under
# OpenCV 4.10 here against the published quad Cortex-A7 time; 97-102 in three runs, docs/hardware.md)
A33_FACTOR = 100.0
PAPER_A33_FPS = 8.9
NETWORK_MODEL = "foranav_oil_palm_cnn.npz"


def pin_to_one_core() -> set[int] | None:
    """Pin this process to one CPU; returns the previous CPU set (None if pinning is not possible)."""
    try:
        previous = os.sched_getaffinity(0)
        os.sched_setaffinity(0, {sorted(previous)[0]})
        return previous
    except (AttributeError, OSError):
        return None


def frames_for(width: int, height: int, seed: int, count: int = 4) -> list[np.ndarray]:
    scale = width / 352.0
    diameters = (CROWNS_AT_352[0] * scale, CROWNS_AT_352[1] * scale)
    return [synthetic.scene(seed + i, width, height, palms=2, roofs=1, diameter=diameters)[0] for i in range(count)]


def time_fast(detector: Any, frames: Sequence[np.ndarray], count: int) -> tuple[np.ndarray, np.ndarray]:
    """(wall ms, CPU ms) of `count` detect() calls."""
    for frame in frames:
        detector.detect(frame)  # warm-up: plans and buffers for this frame size
    times, cpu = [], []
    for i in range(count):
        frame = frames[i % len(frames)]
        start, start_cpu = time.perf_counter(), time.process_time()
        detector.detect(frame)
        times.append(time.perf_counter() - start)
        cpu.append(time.process_time() - start_cpu)
    return np.array(times) * 1000.0, np.array(cpu) * 1000.0


def a33_estimate(cpu_ms: float) -> dict:
    """The estimated A33 time and rate of a frame that takes cpu_ms on one core of this host."""
    a33_ms = cpu_ms * A33_FACTOR
    return {"a33_ms": round(a33_ms, 1), "a33_fps": round(1000.0 / a33_ms, 1)}


def time_reference(detector: Any, frames: Sequence[np.ndarray], count: int) -> np.ndarray:
    times = []
    for i in range(count):
        start = time.perf_counter()
        reference.reference_detect(detector, frames[i % len(frames)])
        times.append(time.perf_counter() - start)
    return np.array(times) * 1000.0


def measure(seed: int = 0, model_name: str = "oil_palm", sizes: Sequence[tuple[int, int]] = SIZES,
            fast_frames: int | None = None, reference_frames: int = REFERENCE_FRAMES, grouping: str = "nms") -> dict:
    previous = pin_to_one_core()
    try:
        return _measure(seed, model_name, sizes, fast_frames, reference_frames, previous is not None,
                        detector_core.DetectorSettings(grouping=grouping))
    finally:
        if previous is not None:
            os.sched_setaffinity(0, previous)


def _measure(seed, model_name, sizes, fast_frames, reference_frames, pinned, settings):
    single_threaded()
    model = common.load(model_name)
    results = {}
    for width, height in sizes:
        detector = detector_core.TreeDetector(model, settings)
        frames = frames_for(width, height, seed)
        fast, cpu = time_fast(detector, frames, (fast_frames or FAST_FRAMES).get(width, 40))
        slow = time_reference(detector, frames, reference_frames)
        median = float(np.median(fast))
        results["%dx%d" % (width, height)] = dict({
            "median_ms": round(median, 3), "p90_ms": round(float(np.percentile(fast, 90)), 3),
            "fps": round(1000.0 / median, 1), "reference_ms": round(float(np.median(slow)), 1),
            "speedup_vs_reference": round(float(np.median(slow)) / median, 1),
            "windows": [round(w) for w in detector.window_sizes(width)],
            "cpu_median_ms": round(float(np.median(cpu)), 3)}, **a33_estimate(float(np.median(cpu))))
    network = detector_core.TreeDetector(common.load(os.path.join(DEFAULT_MODULE_DIR, NETWORK_MODEL)), settings)
    _fast, cpu = time_fast(network, frames_for(352, 288, seed), (fast_frames or FAST_FRAMES).get(352, 40))
    results["352x288 with network"] = dict({"cpu_median_ms": round(float(np.median(cpu)), 3)},
                                           **a33_estimate(float(np.median(cpu))))
    peak_kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss  # kilobytes on Linux
    return {"sizes": results, "peak_rss_mb": round(peak_kb / 1024.0, 1), "one_core": pinned,
            "model": common.model_path(model_name), "a33_factor": A33_FACTOR, "grouping": settings.grouping}


def run(args: argparse.Namespace) -> int:
    result = measure(seed=args.seed, model_name=getattr(args, "model", None) or "oil_palm",
                     grouping=getattr(args, "grouping", None) or "nms")
    if getattr(args, "json", False):
        print(json.dumps(result))
        return 0
    print("tree detector, one core (%s), model %s, grouping %s" % (
        "pinned" if result["one_core"] else "not pinned", result["model"], result["grouping"]))
    print("%-10s %9s %9s %8s %13s %9s  %s" % ("frame", "median ms", "p90 ms", "fps", "reference ms", "speed-up",
                                              "windows px"))
    for size, r in result["sizes"].items():
        if "median_ms" in r:
            print("%-10s %9.3f %9.3f %8.1f %13.1f %8.0fx  %s" % (size, r["median_ms"], r["p90_ms"], r["fps"],
                                                               r["reference_ms"], r["speedup_vs_reference"],
                                                               ",".join(str(w) for w in r["windows"])))
    print("peak memory %.1f MB" % result["peak_rss_mb"])
    print("estimated on the JeVois-A33 (host CPU time x %.0f, docs/hardware.md; the paper: %.1f fps):"
          % (result["a33_factor"], PAPER_A33_FPS))
    for size, r in result["sizes"].items():
        if size.startswith("352x288"):
            print("  %-22s host CPU %.3f ms -> A33 %.0f ms, %.1f fps" % (size, r["cpu_median_ms"], r["a33_ms"],
                                                                         r["a33_fps"]))
    return 0
