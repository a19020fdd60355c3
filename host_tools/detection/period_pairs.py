"""Synthetic small-beside-large crown pairs through today's grouping and the period stage (docs/detector.md).

``python -m host_tools.detection.period_pairs FIRST_SEED END_SEED``: per seed, one 352x288 frame of synthetic
palms (host_tools.detection.synthetic): a 65-80 px crown touching a 100-125 px one (centres 0.85-1.0 x the sum
of the radii apart); the shipped oil-palm model with grouping nms (today's), period (estimated from the frame)
and period with the pair's spacing given. Prints, per grouping, the small and large crowns found (a detection
within half a crown of the centre) and the false alarms. Seeded: the same seeds give the same figures.
"""
import math
import sys

import numpy as np

from host_tools.detection import common, synthetic

import foranav_detector as detector_core

FRAME = (352, 288)
SMALL_PX, LARGE_PX, CLOSENESS = (65.0, 80.0), (100.0, 125.0), (0.85, 1.0)
MATCH_CROWN = 0.5


def pair_frame(seed: int) -> tuple[np.ndarray, list[tuple[float, float, float]], float]:
    """(BGR frame, [(x, y, crown px) of the small and the large crown], their centre distance in px)."""
    rng = np.random.RandomState(seed)
    image = synthetic.ground(rng, FRAME[1], FRAME[0])
    small, large = float(rng.uniform(*SMALL_PX)), float(rng.uniform(*LARGE_PX))
    distance = (small + large) / 2.0 * float(rng.uniform(*CLOSENESS))
    cx, cy = FRAME[0] / 2.0, FRAME[1] / 2.0
    crowns = [(cx - distance / 2.0, cy, small), (cx + distance / 2.0, cy, large)]
    synthetic.draw_palm(image, rng, crowns[1][0], cy, large)
    synthetic.draw_palm(image, rng, crowns[0][0], cy, small)
    return image, crowns, distance


def found(detections, crowns) -> list[bool]:
    return [any(math.hypot(d.x - x, d.y - y) <= MATCH_CROWN * crown for d in detections) for x, y, crown in crowns]


def measure(seeds: range) -> dict:
    model = common.load("oil_palm")
    totals = {name: {"small": 0, "large": 0, "false_alarms": 0} for name in ("nms", "period", "period given")}
    for seed in seeds:
        image, crowns, distance = pair_frame(seed)
        for name in totals:
            settings = detector_core.DetectorSettings(grouping=name.split()[0],
                                                      period_px=distance if name.endswith("given") else None)
            detections = detector_core.TreeDetector(model, settings).detect(image)
            hits = found(detections, crowns)
            totals[name]["small"] += hits[0]
            totals[name]["large"] += hits[1]
            totals[name]["false_alarms"] += sum(1 for d in detections if not any(found([d], crowns)))
    return {"seeds": [seeds.start, seeds.stop - 1], "frames": len(seeds), "groupings": totals}


def main(argv: list[str]) -> int:
    result = measure(range(int(argv[0]), int(argv[1])))
    print("seeds %d-%d, %d frames: small crown found, large found, false alarms" % (
        result["seeds"][0], result["seeds"][1], result["frames"]))
    for name, row in result["groupings"].items():
        print("  %-13s %4d %4d %4d" % (name, row["small"], row["large"], row["false_alarms"]))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
