"""Score the photo-row flights of docs/photo-flights.md: one row of each held-out estate photo per flight.

    python docs/measure/photo_rows.py RUNS MODEL

RUNS holds rows/NAME.json (the maps `foranav plantation --photo ... --rows K` wrote) and flights/NAME.json (the
`foranav fly --json` output of each). Prints the per-flight table, the totals, and each missed target's cause:
time limit (the flight did not complete), else a frame rendered straight above the tree at the map altitude,
through the same camera module and MODEL: no detection within half a crown = detector, else app rule.
"""
import glob
import json
import math
import os
import sys

from host_tools.flight.vision_camera import VisionCamera, model_option, parse_detections
from host_tools.maps import load_map


def flights(runs):
    for path in sorted(glob.glob(os.path.join(runs, "flights", "*.json"))):
        try:
            with open(path) as handle:
                summary = json.load(handle)
        except (OSError, ValueError):
            continue  # a flight that wrote no summary (refused map): listed by the shell loop's .err
        name = os.path.basename(path)[:-5]
        yield name, load_map(os.path.join(runs, "rows", name + ".json")), summary


def miss_cause(pmap, summary, tree_id, camera):
    if not summary["completed"]:
        return "time limit"
    tree = pmap.tree(tree_id)
    frame = camera.render((tree.x, tree.y, pmap.altitude_m, 0.0))
    detections = parse_detections(camera.process(frame.image), 352, 288)
    crown_px = tree.crown_m / camera.camera.metres_per_pixel(pmap.altitude_m)
    seen = any(math.hypot(u - 176, v - 144) <= 0.5 * crown_px for u, v in detections)
    return "app rule (seen from above, not reached)" if seen else "detector (not seen from straight above)"


def main(runs, model):
    print("| flight (photo_row) | targets | reached once | non-targets visited | mean deviation (m) | mission (s) "
          "| completed |")
    print("|---|---|---|---|---|---|---|")
    totals = dict(flights=0, targets=0, once=0, clean=0)
    deviations, causes, photos_visiting = [], {}, {}
    for name, pmap, summary in flights(runs):
        targets = {t.id for t in pmap.targets}
        reached = [r["id"] for r in summary["reached"]]
        own = [r["deviation_m"] for r in summary["reached"] if r["id"] in targets]
        once = sum(1 for i in targets if reached.count(i) == 1)
        others = sorted({i for i in reached if i not in targets})
        missed = [i for i in targets if reached.count(i) != 1]
        if missed:
            camera = VisionCamera(pmap, seed=summary["seed"], model=model_option(model))
            for tree_id in missed:
                cause = miss_cause(pmap, summary, tree_id, camera)
                causes[cause] = causes.get(cause, 0) + 1
        deviations += own
        photo = name.rsplit("_r", 1)[0]
        photos_visiting[photo] = photos_visiting.get(photo, False) or bool(others)
        totals["flights"] += 1
        totals["targets"] += len(targets)
        totals["once"] += once
        totals["clean"] += not others
        mean = "%.3f" % (sum(own) / len(own)) if own else "-"
        print("| %s | %d | %d | %d | %s | %.1f | %s |" % (name, len(targets), once, len(others), mean,
                                                          summary["mission_time_s"], summary["completed"]))
    n = max(totals["flights"], 1)
    print("\n%d flights: %d of %d targets reached exactly once (%.1f %%); no non-target visited in %d of %d "
          "flights; mean deviation %.3f m over %d reached targets"
          % (totals["flights"], totals["once"], totals["targets"], 100.0 * totals["once"] / max(totals["targets"], 1),
             totals["clean"], totals["flights"], sum(deviations) / max(len(deviations), 1), len(deviations)))
    print("no non-target visited in %d of %d photos (all their row flights)"
          % (sum(1 for visited in photos_visiting.values() if not visited), len(photos_visiting)))
    print("misses: %s" % (", ".join("%s %d" % item for item in sorted(causes.items())) or "none"))
    return 0 if n else 1


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:3]))
