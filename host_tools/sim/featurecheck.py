"""Measure the paper's detection cues on rendered crops: do the renderers separate the classes as the paper says?

Cues (definitions in jevois_module/ForaNavTrees/foranav_features.py, the detector's one definition):
- bottom-layer global HOG variance of the full-resolution value window: oil palm above coconut and date palm;
- hue/saturation similarity with an oil-palm template: oil palm above roofs and road crossings.

Crops are single specimens seen by the default 352x288 camera at 1.25 m (host_tools.sim.specimens), window
1.3 x the crown or object size, sizes 0.3-0.45 m, random rotation and lighting per seed.
"""
import argparse
import csv
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from host_tools.sim.specimens import KINDS, render_specimen
from host_tools.sim.world import NO_EFFECTS, SENSOR_EFFECTS, Effects
from jevois_module.ForaNavTrees import foranav_colour as colours
from jevois_module.ForaNavTrees import foranav_features as features  # the detector's definitions of the cues

WINDOW_FACTOR = 1.3
TEMPLATE_SEED_BASE = 1_000_000  # template crops never share a seed with measured crops


@dataclass(frozen=True)
class ClassStats:
    kind: str
    count: int
    hog_variance_median: float
    hog_variance_mean: float
    hs_similarity_median: float
    hs_similarity_mean: float
    hog_variances: tuple = ()
    hs_similarities: tuple = ()


def win_rate(higher: Sequence[float], lower: Sequence[float]) -> float:
    """Fraction of (a, b) pairs, a from ``higher`` and b from ``lower``, with a > b (ties count half): the
    probability that a random crop of one class scores above a random crop of the other (ROC AUC)."""
    a = np.asarray(higher, float)[:, None]
    b = np.asarray(lower, float)[None, :]
    return float(((a > b).sum() + 0.5 * (a == b).sum()) / (a.size * b.size))


def crops(kind: str, count: int, seed: int = 0, effects: Effects = NO_EFFECTS) -> list[np.ndarray]:
    rng = np.random.default_rng([seed, 11])
    return [render_specimen(kind, int(s), window_factor=WINDOW_FACTOR, yaw_deg=float(rng.uniform(0, 360)),
                            effects=effects)
            for s in rng.integers(0, 2 ** 31 - 1, count)]


def oil_palm_template(count: int = 12, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Mean hue and saturation histograms of oil-palm crops (the template I-T)."""
    hists = [colours.hs_histograms(features.bgr_to_hsv(c))
             for c in crops("oil_palm", count, TEMPLATE_SEED_BASE + seed)]
    return np.mean([h for h, _ in hists], axis=0), np.mean([s for _, s in hists], axis=0)


def measure(kinds: Sequence[str], count_per_kind: int, seed: int = 0, template: tuple | None = None,
            effects: Effects = NO_EFFECTS) -> dict[str, ClassStats]:
    """{kind: ClassStats} over count_per_kind crops of each kind (the template is always effect-free)."""
    template_h, template_s = template if template is not None else oil_palm_template(seed=seed)
    out = {}
    for kind in kinds:
        variances, similarities = [], []
        for crop in crops(kind, count_per_kind, seed, effects):
            hsv = features.bgr_to_hsv(crop)
            variances.append(features.hog_global_variance(hsv[..., 2]))
            similarities.append(colours.hs_similarity(hsv, template_h, template_s))
        out[kind] = ClassStats(kind, len(variances), float(np.median(variances)), float(np.mean(variances)),
                               float(np.median(similarities)), float(np.mean(similarities)),
                               tuple(variances), tuple(similarities))
    return out


def format_table(stats: dict[str, ClassStats]) -> str:
    lines = ["| class | crops | HOG variance median (mean) | H/S similarity median (mean) |",
             "|---|---|---|---|"]
    for s in stats.values():
        lines.append("| %s | %d | %.4f (%.4f) | %.3f (%.3f) |" % (s.kind, s.count, s.hog_variance_median,
                                                              s.hog_variance_mean, s.hs_similarity_median,
                                                              s.hs_similarity_mean))
    return "\n".join(lines)


def format_win_rates(stats: dict[str, ClassStats], target: str = "oil_palm") -> str:
    lines = []
    for other, attr, cue in (("coconut", "hog_variances", "HOG variance"),
                             ("date_palm", "hog_variances", "HOG variance"),
                             ("roof", "hs_similarities", "H/S similarity"),
                             ("road_cross", "hs_similarities", "H/S similarity")):
        if target in stats and other in stats:
            lines.append("P(%s %s > %s) = %.3f" % (target, cue, other,
                                                     win_rate(getattr(stats[target], attr),
                                                              getattr(stats[other], attr))))
    return "\n".join(lines)


def measure_dataset(crops_csv: str | os.PathLike, template: tuple) -> dict[str, ClassStats]:
    """{category: ClassStats} over the crops of a ``foranav synth`` dataset (crops/crops.csv)."""

    root = Path(crops_csv).parent
    values = {}
    with open(crops_csv, newline="") as handle:
        for row in csv.DictReader(handle):
            hsv = features.bgr_to_hsv(cv2.imread(str(root / row["image"])))
            values.setdefault(row["category"], []).append(
                (features.hog_global_variance(hsv[..., 2]), colours.hs_similarity(hsv, *template)))
    out = {}
    for category in sorted(values, key=lambda c: (c != "oil_palm", c)):
        v, h = zip(*values[category])
        out[category] = ClassStats(category, len(v), float(np.median(v)), float(np.mean(v)), float(np.median(h)),
                                   float(np.mean(h)), v, h)
    return out


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description="Measure the detector's cues on rendered crops.")
    parser.add_argument("count", nargs="?", type=int, default=30, help="specimen crops per class (default 30)")
    parser.add_argument("--sensor", action="store_true", help="apply the sensor effects to the specimens")
    parser.add_argument("--dataset", help="measure a synth dataset's crops/crops.csv instead of specimens")
    args = parser.parse_args(argv)
    if args.dataset:
        result = measure_dataset(args.dataset, oil_palm_template())
    else:
        result = measure(KINDS, args.count, effects=SENSOR_EFFECTS if args.sensor else NO_EFFECTS)
    print(format_table(result))
    print(format_win_rates(result))


if __name__ == "__main__":
    main()
