"""foranav bench recall: how often the camera module sees the crown under the MAV, by case.

Per case, ``count`` rendered frames of a one-tree-or-more plantation, each run through the JeVois module
(``VisionCamera``: the camera's own code, serial lines parsed back). The target oil palm stands at the
origin; its crown (0.30-0.45 m) and the height (1.0-1.5 m) are drawn from ``foranav plantation``'s default
ranges; yaw is 0 or 180 deg (flying along the column) +/- 5 deg (normal); the height +/- 3 %.

Cases (neighbours stand on the column line, centre distance = the sum of the radii +/- 2 cm: touching):

- isolated: the target alone;
- touching: one neighbour;
- between: a neighbour on each side (a cluster of three);
- small: a small crown (0.30-0.34 m) high up (1.3-1.5 m, so 65-84 px) touching a larger one (0.34-0.45 m),
  the geometry of sweep flight 43;

each with the camera over the target ("centre") and, for isolated and touching, 8-22 cm off it in a random
direction ("off"). A hit: a detection within half a crown of the target (``MATCH_RADIUS_CROWN``); neighbour
recall counts the complete neighbours likewise; a false alarm is a detection within half a crown of no tree.
Seeded: the same seed and count give the same figures. ``--grouping period`` runs the module with its
period-tied peak stage (``grouping period``) instead of today's grouping: with ``--period auto`` the period from
each frame, with ``--period map`` the scene's own spacing (the target's nearest neighbour, in pixels at the
camera's height) sent as ``periodpx``, as a flight map would give it (isolated: auto).
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import math

import numpy as np

from host_tools.detection import common
from host_tools.flight.vision_camera import MATCH_RADIUS_CROWN, VisionCamera, model_option, parse_detections
from host_tools.maps import PlantationMap, Tree
from host_tools.sim.cli_args import appearance_from_args
from host_tools.sim.crowns import AppearanceSpec
from jevois_module.ForaNavTrees.foranav_detector import GROUPINGS

DEFAULT_COUNT = 150  # frames per case
CROWN_M = (0.30, 0.45)  # foranav plantation's --crown-m default
ALTITUDE_M = (1.0, 1.5)  # foranav plantation's --altitude-m default
SMALL_CROWN_M, SMALL_ALTITUDE_M, LARGER_CROWN_M = (0.30, 0.34), (1.3, 1.5), (0.34, 0.45)
TOUCH_M = (-0.02, 0.02)  # centre distance - sum of the radii
OFF_CENTRE_M = (0.08, 0.22)
YAW_SD_DEG = 5.0
HEIGHT_SPREAD = 0.03
NEIGHBOUR_SIDES = {"isolated": 0, "touching": 1, "small": 1, "between": 2}
CASES = (("centre", "isolated"), ("centre", "touching"), ("centre", "between"), ("centre", "small"),
         ("off", "isolated"), ("off", "touching"))
CROWN_PX_BINS = ((0, 80), (80, 95), (95, 115), (115, 10000))
FRAME_SIZE = (352, 288)
TARGET_ID = 1
DEFAULT_GROUPING = GROUPINGS[0]  # the camera module's default: today's grouping


@dataclasses.dataclass
class CaseResult:
    where: str
    case: str
    frames: int
    target_recall: float
    neighbour_recall: float | None
    false_alarms_per_frame: float


def _scene(rng: np.random.Generator, case: str) -> PlantationMap:
    small = case == "small"
    crown = float(rng.uniform(*(SMALL_CROWN_M if small else CROWN_M)))
    altitude = float(rng.uniform(*(SMALL_ALTITUDE_M if small else ALTITUDE_M)))
    trees = [Tree(TARGET_ID, 0.0, 0.0, "oil_palm", crown, True)]
    sides = [-1, 1] if NEIGHBOUR_SIDES[case] == 2 else [int(rng.choice([-1, 1]))] * NEIGHBOUR_SIDES[case]
    for k, side in enumerate(sides):
        other = float(rng.uniform(*(LARGER_CROWN_M if small else CROWN_M)))
        distance = (crown + other) / 2.0 + float(rng.uniform(*TOUCH_M))
        trees.append(Tree(TARGET_ID + 1 + k, side * distance, 0.0, "oil_palm", other, True))
    return PlantationMap("recall", altitude, ((-1.0, 0.0), (1.0, 0.0)), tuple(trees), (), int(rng.integers(2 ** 31)))


def _camera_pose(rng: np.random.Generator, where: str, altitude: float) -> tuple[float, float, float, float]:
    yaw = float(rng.choice([0.0, 180.0]) + rng.normal(0.0, YAW_SD_DEG))
    x = y = 0.0
    if where == "off":
        radius, angle = float(rng.uniform(*OFF_CENTRE_M)), float(rng.uniform(0.0, 2.0 * math.pi))
        x, y = radius * math.cos(angle), radius * math.sin(angle)
    return x, y, altitude * float(rng.uniform(1.0 - HEIGHT_SPREAD, 1.0 + HEIGHT_SPREAD)), yaw


def _map_spacing_px(camera: VisionCamera, pmap: PlantationMap, height_m: float) -> float:
    """The distance from the target to its nearest neighbour, in pixels at this height (what the flight map's
    spacing gives)."""
    target = pmap.trees[0]
    spacing_m = min(math.hypot(t.x - target.x, t.y - target.y) for t in pmap.trees[1:])
    return spacing_m / camera.camera.metres_per_pixel(height_m)


def _near(pixel, tree) -> bool:
    return math.hypot(pixel[0] - tree.u, pixel[1] - tree.v) <= MATCH_RADIUS_CROWN * tree.w


def measure(model: str, count: int = DEFAULT_COUNT, seed: int = 0, appearance: AppearanceSpec | None = None,
            grouping: str = DEFAULT_GROUPING, period: str = "auto") -> dict:
    """{"cases": [CaseResult as dict], "by_crown_px": [...]} for the model (path or shipped species); appearance:
    the trees drawn from photo crowns (foranav bench recall --crowns CSV ...); grouping: the module's
    ``grouping`` parameter (nms, today's; period, the period-tied peak stage); period: "auto" (from each frame)
    or "map" (the scene's neighbour spacing sent as ``periodpx``)."""
    common.load(model)  # a missing or damaged file: one line, before any frame is rendered
    path = model_option(common.model_path(model))  # absolute: the module joins a relative name to its folder
    cases, target_hits_by_px = [], []
    for index, (where, case) in enumerate(CASES):
        rng = np.random.default_rng([int(seed) & 0xFFFFFFFF, index])
        hits = neighbours = neighbour_hits = false_alarms = 0
        for _ in range(count):
            pmap = _scene(rng, case)
            camera = VisionCamera(pmap, seed=int(rng.integers(2 ** 31)), model=path, appearance=appearance,
                                  module_params={"grouping": grouping})
            pose = _camera_pose(rng, where, pmap.altitude_m)
            if period == "map" and len(pmap.trees) > 1:
                camera.runner.setpar("periodpx", "%.1f" % _map_spacing_px(camera, pmap, pose[2]))
            frame = camera.render(pose)
            detections = parse_detections(camera.process(frame.image), *FRAME_SIZE)
            complete = [t for t in frame.trees if t.complete]
            target = [t for t in complete if t.id == TARGET_ID]
            hit = bool(target) and any(_near(d, target[0]) for d in detections)
            hits += hit
            if target:
                target_hits_by_px.append((target[0].w, hit))
            others = [t for t in complete if t.id != TARGET_ID]
            neighbours += len(others)
            neighbour_hits += sum(1 for t in others if any(_near(d, t) for d in detections))
            false_alarms += sum(1 for d in detections if not any(_near(d, t) for t in complete))
        cases.append(CaseResult(where, case, count, hits / count, neighbour_hits / neighbours if neighbours else None,
                                false_alarms / count))
    by_px = []
    for low, high in CROWN_PX_BINS:
        chosen = [hit for px, hit in target_hits_by_px if low <= px < high]
        if chosen:
            by_px.append({"crown_px": [low, high], "frames": len(chosen), "target_recall": float(np.mean(chosen))})
    return {"model": path, "seed": int(seed), "frames_per_case": count, "grouping": grouping, "period": period,
            "crowns": list(appearance.crowns) if appearance is not None else [],
            "cases": [dataclasses.asdict(c) for c in cases], "by_crown_px": by_px}


def run(args: argparse.Namespace) -> int:
    spec, _loaded = appearance_from_args(args, ("oil_palm",), "foranav bench recall")
    result = measure(getattr(args, "model", None) or "oil_palm", getattr(args, "count", None) or DEFAULT_COUNT,
                     getattr(args, "seed", 0), None if spec.default else spec,
                     getattr(args, "grouping", None) or DEFAULT_GROUPING, getattr(args, "period", None) or "auto")
    if getattr(args, "json", False):
        print(json.dumps({"recall": result}, indent=2))
        return 0
    print("model %s, grouping %s%s, %d rendered frames per case, seed %d%s" % (
        result["model"], result["grouping"],
        " (period %s)" % result["period"] if result["grouping"] == "period" else "", result["frames_per_case"],
        result["seed"],
        ", photo crowns from %s" % ", ".join(result["crowns"]) if result["crowns"] else ""))
    print("%-7s %-9s %15s %16s %18s" % ("camera", "case", "target recall", "neighbour recall",
                                        "false alarms/frame"))
    for c in result["cases"]:
        neighbour = "-" if c["neighbour_recall"] is None else "%.1f %%" % (100 * c["neighbour_recall"])
        print("%-7s %-9s %13.1f %% %16s %18.3f" % (c["where"], c["case"], 100 * c["target_recall"], neighbour,
                                                   c["false_alarms_per_frame"]))
    for row in result["by_crown_px"]:
        low, high = row["crown_px"]
        label = "over %d px" % low if high >= CROWN_PX_BINS[-1][1] else "%d-%d px" % (low, high)
        print("crown %-12s target recall %.1f %% (%d frames, all cases)" % (label, 100 * row["target_recall"],
                                                                           row["frames"]))
    return 0
