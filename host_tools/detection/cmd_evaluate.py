"""Evaluate a detector model: the paper's crop protocol and frame-level detection.

Example: foranav evaluate --model oil_palm --data holdout/crops/crops.csv holdout/frames/boxes.csv --json
Crops CSVs (image,class,category; written by foranav synth) are classified crop by crop; boxes CSVs give
frame-level precision, recall, F1 and centre error, and, when no crops CSV is given, --crops positive and
negative crops cut from their frames (seeded). Paper figures for oil palm: accuracy 92.91 %, precision
90.37 %, recall 96.06 %.
"""
import json

from host_tools.detection import common, dataset, evaluation
from host_tools.detection.threads import single_threaded

PAPER = {"accuracy": 0.9291, "precision": 0.9037, "recall": 0.9606}


def add_arguments(parser):
    parser.add_argument("--model", required=True, help="model file, or a shipped species (oil_palm, citrus, olive)")
    parser.add_argument("--data", nargs="+", required=True, metavar="CSV", help="boxes CSVs and/or crops CSVs")
    parser.add_argument("--crops", type=int, default=120, help="crops of each class cut from frames (default 120)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the crops cut from frames (default 0)")
    parser.add_argument("--json", action="store_true", help="print one JSON object")


def run(args):
    single_threaded()
    model = common.load(args.model)
    crop_csvs = [p for p in args.data if evaluation.is_crops_csv(p)]
    frame_csvs = [p for p in args.data if p not in crop_csvs]
    frames = dataset.load_frames(frame_csvs) if frame_csvs else []
    if crop_csvs:
        crops = [c for path in crop_csvs for c in evaluation.read_crops(path)]
        result = evaluation.evaluate_crop_images(model, crops)
        result["crop_source"] = "crops CSV"
    else:
        crops = evaluation.sample_frame_crops(frames, model.species, model.window_margin, args.crops, args.crops,
                                              args.seed)
        result = evaluation.evaluate_frame_crops(model, crops)
        result["crop_source"] = "cut from frames (seed %d)" % args.seed
    result = dict({"model": common.model_path(args.model), "species": model.species}, **result)
    if frames:
        result["frames"] = evaluation.evaluate_frames(model, frames)
    if args.json:
        print(json.dumps(result))
        return 0
    print("%s (%s), crops %s: accuracy %.2f %%, precision %.2f %%, recall %.2f %% (n_pos %d, n_neg %d); "
          "paper 92.91 / 90.37 / 96.06 %%" % (result["model"], model.species, result["crop_source"],
                                              100 * result["accuracy"], 100 * result["precision"],
                                              100 * result["recall"], result["n_pos"], result["n_neg"]))
    if frames:
        f = result["frames"]
        error = "n/a" if f["centre_error_px_mean"] is None else "%.1f px (median %.1f)" % (
            f["centre_error_px_mean"], f["centre_error_px_median"])
        print("frames: %d frames, %d trees, %d detections: precision %.2f %%, recall %.2f %%, F1 %.2f %%, "
              "centre error %s" % (f["n_frames"], f["n_trees"], f["n_detections"], 100 * f["precision"],
                                   100 * f["recall"], 100 * f["f1"], error))
    return 0
