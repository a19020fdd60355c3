"""Train a detector model from annotated CSVs (the shared boxes format; image paths relative to each CSV).

Example: foranav train --species oil_palm --data runs/synth/frames/boxes.csv --seed 11 --out model.npz
Boxes of the species wholly inside their frame are positives; other labels, windows cutting a tree and
background windows are negatives; the window follows each box (crown x --margin). A linear SVM is trained
with hard-negative mining; the colour template and the colour and variance thresholds come from the
positives. Same data and seed, same model file.
"""
from host_tools import fileio
from host_tools.detection import dataset, evaluation, training
from host_tools.detection.threads import single_threaded
from host_tools.errors import ForaNavError

import foranav_model


def add_arguments(parser):
    parser.add_argument("--species", required=True, help="label of the target trees in the CSVs, e.g. oil_palm")
    parser.add_argument("--data", nargs="+", required=True, metavar="CSV",
                        help="boxes CSVs (frames), optionally also crops CSVs (image,class,category) of ready windows")
    parser.add_argument("--seed", type=int, default=0, help="seed of every random choice (default 0)")
    parser.add_argument("--out", required=True, metavar="MODEL", help="model file to write (.npz)")
    parser.add_argument("--windows", default=",".join(str(w) for w in training.DEFAULT_WINDOW_SIZES),
                        help="detection window sides in pixels at --reference-width (default %(default)s)")
    parser.add_argument("--reference-width", type=int, default=training.DEFAULT_REFERENCE_WIDTH,
                        help="frame width the window sizes refer to (default %(default)s: the flight camera)")
    parser.add_argument("--margin", type=float, default=training.DEFAULT_MARGIN,
                        help="window side / crown size (default %(default)s)")
    parser.add_argument("--quiet", action="store_true", help="print only the summary line")


def run(args):
    fileio.check_output_file(args.out)  # before the training run, not after it
    single_threaded()
    try:
        windows = tuple(int(w) for w in args.windows.split(","))
    except ValueError:
        raise ForaNavError("--windows must be comma-separated integers")
    if min(windows) < 24 or args.margin <= 0 or args.reference_width <= 0:
        raise ForaNavError("--windows must be >= 24 px, --margin and --reference-width positive")
    crop_csvs = [p for p in args.data if evaluation.is_crops_csv(p)]
    frames = dataset.load_frames([p for p in args.data if p not in crop_csvs])
    crops = [(dataset.read_image(path), positive) for csv_path in crop_csvs
             for path, positive, _category in evaluation.read_crops(csv_path)]
    log = (lambda message: None) if args.quiet else (lambda message: print("train: " + message))
    try:
        model = training.train(frames, args.species, seed=args.seed, window_sizes=windows,
                               reference_width=args.reference_width, margin=args.margin, log=log, crops=crops)
    except ValueError as err:
        raise ForaNavError(str(err))
    with fileio.atomic_path(args.out) as tmp:
        with open(str(tmp), "wb") as handle:
            foranav_model.save_model(model, handle)
    print("wrote %s: %s, svm bias %.3f, thresholds svm %.2f var %.4g hs %.3f edge %.2f"
          % (args.out, model.notes, model.svm_bias, model.svm_threshold, model.variance_threshold,
             model.hs_threshold, model.edge_threshold))
    return 0
