"""Evaluate a detector model as a user judges it: whole frames per imagery, and the paper's crop protocol.

Example: foranav evaluate --model m.npz --data held_out/siteA/boxes.csv --crown-px 160 --hull --plot pr.png
Frame level, per boxes CSV (an imagery): the detector on every frame (every tree reported); a detection is a
hit when its centre lies in a not yet matched complete box of the species. Precision, recall, F1, centre
error of the hits, false alarms per image and those on look-alike boxes, the funnel (how many crowns survive
each stage: SVM, score-map peak, candidate cap, NMS, colour, texture), and the domain used. --hull scores only
inside each image's annotated area (sites that annotate one block). Scale as in `foranav detect`
(--crown-px N or boxes: each image's median box; --gsd/--crown-m). --plot writes a precision-recall PNG.
Crop level: the paper's protocol on crops CSVs (image,class,category; written by foranav synth), else on
--crops positive and negative crops cut from the frames (seeded). Paper figures for oil palm: accuracy
92.91 %, precision 90.37 %, recall 96.06 %.
"""
import argparse
import json

from host_tools import argtypes, fileio
from host_tools.detection import common, dataset, evaluation
from host_tools.threads import single_threaded
from host_tools.errors import ForaNavError
from host_tools.plotting import plt

import foranav_detector as detector_core
import foranav_model

PAPER = {"accuracy": 0.9291, "precision": 0.9037, "recall": 0.9606}


MAX_CROPS = 10000  # crops of each class: 48x48 HSV windows, 70 MB at this count


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--model", required=True, help="model file, or a shipped species (oil_palm, citrus, olive)")
    parser.add_argument("--data", nargs="+", action="extend", default=[], metavar="CSV",
                        help="boxes CSVs and/or crops CSVs (repeat or list several)")
    parser.add_argument("--domain", action="append", default=[], metavar="NAME=CSV",
                        help="score this boxes CSV with the model's imagery NAME (default: the nearest in colour)")
    parser.add_argument("--crown-px", metavar="N|boxes", help="typical crown diameter, pixels, or 'boxes' (each "
                        "image's median annotated crown); default: windows follow the frame width")
    parser.add_argument("--gsd", type=float, metavar="M_PER_PX", help="metres per pixel (with --crown-m)")
    parser.add_argument("--crown-m", type=float, metavar="M", help="typical crown diameter, metres (with --gsd)")
    parser.add_argument("--hull", action="store_true", help="score only inside each image's annotated area")
    parser.add_argument("--max-detections", type=argtypes.int_range(*common.MAX_DETECTIONS_RANGE), metavar="N", help="at most N trees per frame (default: all)")
    parser.add_argument("--crops", type=argtypes.int_range(1, MAX_CROPS), default=120, help="crops of each class cut from frames (default 120)")
    parser.add_argument("--seed", type=argtypes.seed, default=0, help="seed of the crops cut from frames (default 0)")
    parser.add_argument("--plot", metavar="PNG", help="write the precision-recall curve of each imagery here")
    parser.add_argument("--json", action="store_true", help="print one JSON object")


def run(args: argparse.Namespace) -> int:
    if args.plot is not None:
        fileio.check_figure_file(args.plot, "--plot")
    single_threaded()
    model = common.load(args.model)
    crown_px = common.crown_pixels(args, boxes=True)
    if args.max_detections is not None and args.max_detections < 1:
        raise ForaNavError("--max-detections must be at least 1")
    if args.crops < 1 or args.seed < 0:
        raise ForaNavError("--crops must be at least 1 and --seed not negative")
    explicit = {}
    for item in args.domain:
        name, sep, path = item.partition("=")
        if not sep or not path:
            raise ForaNavError("--domain must be NAME=CSV, got %r" % item)
        try:
            model.domain(name)
        except foranav_model.ModelFormatError as err:
            raise ForaNavError("--domain: %s" % err)
        explicit[path] = name
    paths = list(args.data) + [p for p in explicit if p not in args.data]
    if not paths:
        raise ForaNavError("--data: give at least one CSV")
    crop_csvs = [p for p in paths if evaluation.is_crops_csv(p)]
    frame_csvs = [p for p in paths if p not in crop_csvs]
    imageries = [(path, dataset.load_frames([path])) for path in frame_csvs]
    frames = [f for _path, fs in imageries for f in fs]
    common.check_crown_fits(crown_px, [f.bgr.shape[1::-1] for f in frames], "the frames of --data")
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
    per_imagery = {}
    for path, imagery_frames in imageries:
        settings = detector_core.DetectorSettings(max_detections=args.max_detections, domain=explicit.get(path))
        per_imagery[path] = evaluation.evaluate_frames(model, imagery_frames, settings, hull=args.hull,
                                                       crown_px=crown_px, funnel=True)
    if per_imagery:
        result["imageries"] = {path: _public(r) for path, r in per_imagery.items()}
        result["frames"] = _public(evaluation.combine(list(per_imagery.values())))
    if args.plot and per_imagery:
        _plot(per_imagery, args.plot)
    if args.json:
        print(json.dumps(result))
        return 0
    print("%s (%s), crops %s: accuracy %.2f %%, precision %.2f %%, recall %.2f %% (n_pos %d, n_neg %d); "
          "paper 92.91 / 90.37 / 96.06 %%" % (result["model"], model.species, result["crop_source"],
                                              100 * result["accuracy"], 100 * result["precision"],
                                              100 * result["recall"], result["n_pos"], result["n_neg"]))
    for path, f in per_imagery.items():
        error = "n/a" if f["centre_error_px_mean"] is None else "%.1f px (median %.1f)" % (
            f["centre_error_px_mean"], f["centre_error_px_median"])
        print("%s: %d frames, %d trees, %d detections: precision %.2f %%, recall %.2f %%, F1 %.2f %%, centre error %s; "
              "false alarms per image %.2f (on look-alikes %.2f); domain %s"
              % (path, f["n_frames"], f["n_trees"], f["n_detections"], 100 * f["precision"], 100 * f["recall"],
                 100 * f["f1"], error, f["false_alarms_per_image"], f["lookalike_false_alarms_per_image"],
                 ", ".join("%s x%d" % item for item in f["domains"].items())))
        print("  funnel: %d crowns; %s" % (f["n_trees"], ", ".join("%s %d" % (stage, f["funnel"][stage])
                                                                    for stage in evaluation.FUNNEL_STAGES)))
    return 0


def _public(result):
    return {k: v for k, v in result.items() if k not in ("scored", "centre_errors")}


def _plot(per_imagery, path):
    figure, axis = plt.subplots(figsize=(5.5, 4.5))
    for name, result in per_imagery.items():
        curve = evaluation.precision_recall_curve(result["scored"], result["n_trees"])
        if curve:
            axis.plot([c[2] for c in curve], [c[1] for c in curve], label=name.split("/")[-2] if "/" in name else name)
    axis.set_xlabel("recall")
    axis.set_ylabel("precision")
    axis.set_xlim(0, 1)
    axis.set_ylim(0, 1.02)
    axis.grid(alpha=0.3)
    axis.legend(fontsize=7)
    axis.set_title("Detections by score (operating point: the curve's end)")
    figure.tight_layout()
    fileio.write_figure(figure, path, dpi=90)
    plt.close(figure)
