"""Opt-in: train and evaluate the oil-palm detector on real aerial imagery (../shared/data/real).

    .venv/bin/python -m host_tools.detection.realdata [--real DIR] [--seed N] [--out MODEL] [--json]

Nothing from the real data is written into the repository: the model goes to --out (default
runs/detector/real_oil_palm.npz) and figures to stdout.

Data (see the data folder's README): oil palm boxes from the Kluang UAV tiles (false colour, ~66 px crowns)
and the Google Earth blocks (true colour, ~100-200 px); look-alikes (negatives) from the coconut (Tonga),
olive (Kall-K) and NEON crown sets. Images are split by file (seeded): three quarters to train on, one
quarter held out. Windows follow each box (crown x margin), so every crown is rescaled to the top layer's
24 px whatever its size in the image; detection on whole images uses window sizes derived from the
image's own crown sizes (as a camera at a known altitude would).

Figures: the paper's crop protocol on held-out images (120 positive crowns, 120 negatives: look-alike
crowns, windows cutting a crown, background) and frame-level precision/recall/F1 on the held-out Kluang
tiles (the only fully annotated oil-palm images; the Google Earth sites annotate one block each).
"""
import argparse
import json
from pathlib import Path

import numpy as np

from host_tools import fileio
from host_tools.detection import dataset, evaluation, training
from host_tools.detection.threads import single_threaded
from host_tools.errors import ForaNavError

import foranav_detector as detector_core
import foranav_features as features
import foranav_model

DEFAULT_REAL = Path(__file__).resolve().parents[3] / "shared" / "data" / "real"
OIL_PALM_SETS = ("oilpalm_uav_kluang_narimt", "oilpalm_gearth_detectree2")
LOOKALIKE_SETS = ("coconut_tonga_oam", "olive_kallk", "neon_deepforest")
HELD_OUT = 0.25
MIN_CROWN_PX = 20  # smaller annotated crowns are skipped (below the 24 px top layer)
MAX_FRAMES_PER_SET = 60  # keeps the run to a few minutes
KLUANG_MAX_DETECTIONS = 200  # a tile holds ~45 crowns (the camera default of 8 would cap recall)


def load_split(real, seed):
    rng = np.random.RandomState(seed)
    train, test = [], []
    for name in OIL_PALM_SETS + LOOKALIKE_SETS:
        csv_path = Path(real) / name / "boxes.csv"
        if not csv_path.exists():
            raise ForaNavError("%s: missing (is --real the shared real-data folder?)" % csv_path)
        frames = dataset.load_frames([csv_path])
        for frame in frames:  # one label vocabulary: the target and "other" look-alikes
            frame.boxes = [b for b in frame.boxes if b.label and max(b.width, b.height) >= MIN_CROWN_PX]
            frame.boxes = [b if b.label == "oil_palm" else b.__class__(b.image, b.x_center, b.y_center, b.width,
                                                                        b.height, "lookalike") for b in frame.boxes]
        frames = [f for f in frames if f.boxes]
        order = rng.permutation(len(frames))[:MAX_FRAMES_PER_SET]
        cut = max(1, int(round(HELD_OUT * len(order))))
        test += [(name, frames[i]) for i in sorted(order[:cut])]
        train += [(name, frames[i]) for i in sorted(order[cut:])]
    return train, test


def box_windows(frame, margin):
    """Window sizes for detecting this image's crowns: crown sizes x margin, in W_d steps, at most 3."""
    sizes = sorted({max(1, int(round(dataset.crown_size(b) * margin / features.HOG_WINDOW))) * features.HOG_WINDOW
                    for b in frame.boxes})
    if len(sizes) > 3:
        sizes = [sizes[0], sizes[len(sizes) // 2], sizes[-1]]
    return tuple(s for s in sizes if s <= min(frame.width, frame.height))


def run_experiment(real=DEFAULT_REAL, seed=0, out="runs/detector/real_oil_palm.npz", log=print):
    single_threaded()
    train, test = load_split(real, seed)
    log("real data: %d training images, %d held out" % (len(train), len(test)))
    model = training.train([f for _n, f in train], "oil_palm", seed=seed, log=log, mining_windows=box_windows)
    with fileio.atomic_path(out) as tmp:
        with open(str(tmp), "wb") as handle:
            foranav_model.save_model(model, handle)
    test_frames = [f for _n, f in test]
    crops = evaluation.sample_frame_crops(test_frames, "oil_palm", model.window_margin, 120, 120, seed)
    result = {"model": str(out), "crops": evaluation.evaluate_frame_crops(model, crops)}
    kluang = [f for n, f in test if n == "oilpalm_uav_kluang_narimt"]
    frame_totals = []
    for frame in kluang:
        windows = box_windows(frame, model.window_margin)
        settings = detector_core.DetectorSettings(window_sizes=windows, max_detections=KLUANG_MAX_DETECTIONS)
        frame_totals.append(evaluation.evaluate_frames(model, [frame], settings))
    hits = sum(round(r["recall"] * r["n_trees"]) for r in frame_totals)
    trees = sum(r["n_trees"] for r in frame_totals)
    detections = sum(r["n_detections"] for r in frame_totals)
    precision = hits / float(detections) if detections else 0.0
    recall = hits / float(trees) if trees else 0.0
    result["frames_kluang"] = {
        "n_frames": len(kluang), "n_trees": trees, "n_detections": detections, "precision": precision,
        "recall": recall, "f1": 2 * precision * recall / (precision + recall) if precision + recall else 0.0}
    result["train_images"] = len(train)
    result["held_out_images"] = len(test)
    return result


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--real", default=str(DEFAULT_REAL), help="the shared real-data folder")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", default="runs/detector/real_oil_palm.npz")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    result = run_experiment(args.real, args.seed, args.out, log=(lambda m: None) if args.json else print)
    print(json.dumps(result, indent=None if args.json else 1))


if __name__ == "__main__":
    main()
