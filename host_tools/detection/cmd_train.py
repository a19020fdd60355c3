"""Train a detector model from annotated CSVs (the shared boxes format; image paths relative to each CSV).

Example: foranav train --species oil_palm --data siteA/boxes.csv --data siteB/boxes.csv --seed 1 --out m.npz
Each boxes CSV is one imagery (its folder name; --domain NAME=CSV names it): the model holds one shared SVM
and, per imagery with trees of the species, a colour model and thresholds calibrated on its held-back
frames. An imagery without the species adds negatives only. Boxes of the species wholly inside their frame
are positives; other labels, windows cutting a tree and background windows are negatives; the window
follows each box (crown x --margin). Survey imagery (frames not --reference-width wide) is mined for hard
negatives at its own crown scale, only inside each image's annotated area. A training report (report.md
and PNGs: the share of positives and look-alikes passing each cue, per imagery, with warnings) goes next
to the model (--report). Same data and seed, same model file.
"""
import argparse
import io
import os
import sys
from pathlib import Path

from host_tools import annotations, argtypes, fileio
from host_tools.detection import cnn, dataset, evaluation, report, training
from host_tools.detection.progress import Progress
from host_tools.threads import single_threaded
from host_tools.errors import ForaNavError

import foranav_colour as colours

import foranav_features as features
import foranav_model


REFERENCE_WIDTH_RANGE = foranav_model.REFERENCE_WIDTHS  # px: the flight camera's frame width
MARGIN_RANGE = (0.5, foranav_model.MAX_WINDOW_RATIO)  # training window side / crown size


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--species", required=True, help="label of the target trees in the CSVs, e.g. oil_palm")
    parser.add_argument("--data", nargs="+", action="extend", default=[], metavar="CSV",
                        help="boxes CSVs (one imagery each; repeat or list several), optionally crops CSVs "
                        "(image,class,category) of ready windows")
    parser.add_argument("--domain", action="append", default=[], metavar="NAME=CSV",
                        help="a boxes CSV as the imagery NAME (repeatable)")
    parser.add_argument("--seed", type=int, default=0, help="seed of every random choice (default 0)")
    parser.add_argument("--out", required=True, metavar="MODEL", help="model file to write (.npz)")
    parser.add_argument("--windows", default=",".join(str(w) for w in training.DEFAULT_WINDOW_SIZES),
                        help="camera window sides in pixels at --reference-width (default %(default)s)")
    parser.add_argument("--reference-width", type=argtypes.int_range(*REFERENCE_WIDTH_RANGE),
                        default=training.DEFAULT_REFERENCE_WIDTH,
                        help="frame width the window sizes refer to (default %d: the flight camera; %d..%d)"
                        % ((training.DEFAULT_REFERENCE_WIDTH,) + REFERENCE_WIDTH_RANGE))
    parser.add_argument("--margin", type=argtypes.float_range(*MARGIN_RANGE), default=training.DEFAULT_MARGIN,
                        help="training window side / crown size (default %g; %g..%g)"
                        % ((training.DEFAULT_MARGIN,) + MARGIN_RANGE))
    parser.add_argument("--colour", choices=colours.COLOUR_KINDS, default="templates",
                        help="colour model per imagery: templates (hue/saturation correlation) or linear "
                        "(a classifier on the histograms); default %(default)s")
    parser.add_argument("--colour-templates", type=int, default=1, metavar="K",
                        help="templates per imagery (k-means of the crowns' histograms; default 1)")
    parser.add_argument("--second-stage", choices=features.SECOND_STAGE_KINDS, default=training.DEFAULT_SECOND_KIND,
                        help="descriptor of the survey models' second stage: the 48 px HOG, or it and the "
                        "radial cue (gradients against the lines from the window's centre); default %(default)s")
    parser.add_argument("--second-views", type=int, choices=features.SECOND_STAGE_VIEWS,
                        default=training.DEFAULT_SECOND_VIEWS,
                        help="the second stage scores the window as it is (1) or the mean HOG of its four "
                        "quarter turns (4); default %(default)s")
    parser.add_argument("--cnn", action="store_true",
                        help="survey models: add the learned stage, a small CNN each detection must also pass, run "
                        "on the camera by OpenCV's dnn module (training needs PyTorch: pip install -e '.[train]')")
    parser.add_argument("--provenance", default="", metavar="TEXT",
                        help="sources and licences of the imagery, stored in the model file")
    parser.add_argument("--report", metavar="DIR", help="folder for report.md and its PNGs (default: MODEL "
                        "without .npz + '_report'; 'none': no report)")
    parser.add_argument("--quiet", action="store_true", help="print only the summary line")


def imageries_from(args: argparse.Namespace) -> list[training.Imagery]:
    """[(name, csv path)]: every boxes CSV once, named by --domain or by its folder (made unique)."""
    named = []
    for item in args.domain:
        name, sep, path = item.partition("=")
        if not sep or not name or len(name.split()) != 1 or not path:
            raise ForaNavError("--domain must be NAME=CSV with a one-word NAME, got %r" % item)
        named.append((name, path))
    for path in args.data:
        if not evaluation.is_crops_csv(path):
            base = Path(path).resolve().parent.name or "imagery"
            name, n = base, 2
            while name in [existing for existing, _p in named]:
                name, n = "%s_%d" % (base, n), n + 1
            named.append((name, path))
    names = [name for name, _p in named]
    if len(set(names)) != len(names):
        raise ForaNavError("--domain: imagery names must be unique (%s)" % ", ".join(names))
    if not named:
        raise ForaNavError("--data: no boxes CSV given (crops CSVs alone cannot train a model)")
    return named


def check_out(path: str) -> None:
    """Fail before the work when the model cannot be written there."""
    folder = Path(path).resolve().parent
    if Path(path).is_dir():
        raise ForaNavError("--out %s: is a folder, give a file name" % path)
    existing = folder
    while not existing.exists():
        existing = existing.parent
    if not existing.is_dir() or not os.access(str(existing), os.W_OK):
        raise ForaNavError("--out %s: cannot write in %s" % (path, existing))


def _windows(text: str, reference_width: int) -> tuple[int, ...]:
    """--windows: comma-separated sides, each from the HOG window (24 px) to the shorter side of a frame
    ``reference_width`` wide (every JeVois sensor mode is at least 3/4 as high as it is wide)."""
    try:
        windows = tuple(int(w) for w in text.split(","))
    except ValueError:
        raise ForaNavError("--windows must be comma-separated integers, got %r" % text)
    largest = foranav_model.largest_window(reference_width)
    if min(windows) < features.HOG_WINDOW or max(windows) > largest:
        raise ForaNavError("--windows: each side must be %d..%d px (the frame's shorter side at --reference-width "
                           "%d), got %s" % (features.HOG_WINDOW, largest, reference_width, text))
    return windows


def report_folder(args: argparse.Namespace) -> str | None:
    """--report: the report's folder (default: the model's name without .npz + '_report'); None for 'none'."""
    report_dir = args.report or str(Path(args.out).with_suffix("")) + "_report"
    return None if report_dir == "none" else report_dir


def run(args: argparse.Namespace) -> int:
    fileio.check_output_file(args.out)  # before the training run, not after it
    report_dir = report_folder(args)
    if report_dir is not None:  # checked before the model is replaced: a bad --report must not cost the model
        fileio.check_output_dir(report_dir, "--report")
    single_threaded()
    windows = _windows(args.windows, args.reference_width)
    if not 1 <= args.colour_templates <= 16:
        raise ForaNavError("--colour-templates must be 1..16")
    if not args.data and not args.domain:
        raise ForaNavError("--data or --domain: give at least one boxes CSV")
    check_out(args.out)
    if args.cnn:
        cnn.torch_or_error()  # before the work, not after it
    named = imageries_from(args)
    crop_csvs = [p for p in args.data if evaluation.is_crops_csv(p)]
    progress = Progress(io.StringIO() if args.quiet else sys.stderr)
    progress.plan([("loading images", sum(len(annotations.boxes_by_image(annotations.read_boxes(path)))
                                          for _name, path in named), 1.0)])
    imageries = [training.Imagery(name, dataset.load_frames([path], frame_done=lambda: progress.tick(
        "loading images")), str(path)) for name, path in named]
    crops = [(dataset.read_image(path), positive) for csv_path in crop_csvs
             for path, positive, _category in evaluation.read_crops(csv_path)]
    log = (lambda message: None) if args.quiet else (lambda message: print("train: " + message, flush=True))
    try:
        model = training.train(imageries, args.species, seed=args.seed, window_sizes=windows,
                               reference_width=args.reference_width, margin=args.margin, log=log, crops=crops,
                               colour_kind=args.colour, colour_templates=args.colour_templates,
                               provenance=args.provenance, second_kind=args.second_stage,
                               second_views=args.second_views, cnn=args.cnn, progress=progress)
    except ValueError as err:  # e.g. no complete tree of the species: name the data it looked at
        raise ForaNavError("%s: %s" % (", ".join(str(path) for _name, path in named), err))
    progress.finish()
    with fileio.atomic_path(args.out) as tmp:
        with open(str(tmp), "wb") as handle:
            foranav_model.save_model(model, handle)
    if report_dir is not None:
        written = report.write_report(model, imageries, report_dir, seed=args.seed)
        for warning in written["warnings"]:
            print("train: warning: " + warning)
        log("report: %s" % written["path"])
    thresholds = "; ".join("%s svm %.2f colour %.3f var %.4g%s" % (
        d.name, d.svm_threshold, d.hs_threshold, d.variance_threshold,
        "" if model.second_window is None else " second stage %.2f" % d.second_threshold)
        + ("" if model.cnn_onnx is None else " network %.2f" % d.cnn_threshold) for d in model.domains)
    print("wrote %s: %s, svm bias %.3f, edge %.2f, crown ratios %s; %s"
          % (args.out, model.notes, model.svm_bias, model.edge_threshold,
             ",".join("%.2f" % r for r in model.crown_ratios), thresholds))
    return 0
