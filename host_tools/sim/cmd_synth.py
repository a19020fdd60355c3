"""Write a rendered dataset: the paper's positive/negative crops and annotated full frames.

Example: foranav synth --out data/synth --count 400 --seed 1 [--species oil_palm]

Layout of DIR:
  crops/pos/NNNNN.png    one complete tree of a target species (window 1.15-1.45 x the crown, jittered)
  crops/neg/NNNNN.png    no complete target tree: look-alike species, roof, road_cross, partial, background
  crops/crops.csv        image,class,category  (class pos/neg; image relative to crops/)
  frames/NNNNN.png       352x288 camera frames of random plots
  frames/boxes.csv       image,x_center,y_center,width,height,label (host_tools/annotations.py): every
                         complete tree (label = species) and object (roof, road_cross); frames without any are
                         listed with an empty label
Same seed, same bytes. --species selects the target species (default oil_palm); several, given together or
repeated (--species oil_palm --species olive = --species oil_palm olive), make all of them targets.
--crowns CSV ... draws the trees of the species in those annotation CSVs from their photographs (the crown
library, docs/simulator.md), scaled to the flight camera: crops and frames of real crowns at flight scale.
--touching RATE: in the scenes' rows each tree touches the previous one with probability RATE (crowns meeting
on one line, centre distance = sum of the radii + 0-2 cm, as foranav plantation's clusters); default: the
original scenes (same bytes). 0.15 is the mean of foranav plantation's cluster_rate (docs/simulator.md).
--photo-maps MAP ...: the scenes are photo maps (foranav plantation --photo): views inside their photos at
0.8-1.2 x the map's altitude, the photo's boxes as the frames' ground truth (docs/photo-flights.md).
"""
import argparse
import csv
import io
import shutil
import tempfile
from pathlib import Path

import cv2

from host_tools import argtypes, fileio
from host_tools.annotations import Box, format_boxes
from host_tools.errors import ForaNavError
from host_tools.maps import SPECIES, load_map
from host_tools.sim.cli_args import add_appearance_arguments, appearance_from_args
from host_tools.sim.dataset import generate

CROPS_HEADER = ("image", "class", "category")
MAX_COUNT = 100000  # crops or frames: beyond this a data set no longer fits a laptop's disk
DEFAULT_SPECIES = ("oil_palm",)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--out", required=True, help="output folder (created; existing crops/ and frames/ replaced)")
    parser.add_argument("--count", type=argtypes.int_range(1, MAX_COUNT), required=True,
                        help="positive crops (and as many negatives)")
    parser.add_argument("--frames", type=argtypes.int_range(0, MAX_COUNT), default=None,
                        help="annotated frames (default: --count)")
    parser.add_argument("--seed", type=argtypes.seed, default=0, help="seed (default 0)")
    parser.add_argument("--species", nargs="+", action="extend", choices=SPECIES, default=None,
                        help="target species, repeatable (default oil_palm)")
    parser.add_argument("--touching", type=argtypes.probability, default=None, metavar="RATE",
                        help="probability that a tree touches the previous one of its row (default: the "
                             "original scenes)")
    parser.add_argument("--photo-maps", nargs="+", metavar="MAP", default=None,
                        help="photo maps (foranav plantation --photo): the frames and crops are random views "
                             "inside their photos, their boxes the ground truth, instead of random plots")
    add_appearance_arguments(parser)


def run(args: argparse.Namespace) -> int:
    fileio.check_output_dir(args.out)
    frame_count = args.count if args.frames is None else args.frames
    species = tuple(dict.fromkeys(args.species or DEFAULT_SPECIES))
    _, appearance = appearance_from_args(args, SPECIES, "the synth scenes")
    photo_maps = tuple(load_map(m) for m in args.photo_maps or ())
    for path, pmap in zip(args.photo_maps or (), photo_maps):
        if pmap.photo is None:
            raise ForaNavError("--photo-maps %s: not a photo map (no photo field)" % path)
    positives, negatives, frames = generate(args.seed, args.count, frame_count, species, appearance=appearance,
                                           touching_rate=args.touching, photo_maps=photo_maps)
    try:
        write_into(Path(args.out), positives, negatives, frames)
    except OSError as err:
        raise ForaNavError("%s: cannot write the dataset: %s" % (args.out, err.strerror or err))
    print("wrote %s: %d positive and %d negative crops (target %s), %d frames with %d boxes"
          % (args.out, len(positives), len(negatives), ", ".join(species), len(frames),
             sum(len(f.boxes) for f in frames)))
    if appearance is not None and appearance.library is not None:
        print("crowns from photos: %s" % ", ".join("%s (%d crowns)" % (s, appearance.library.count(s))
                                                   for s in appearance.library.species))
    return 0


def write_into(out: Path, positives: list, negatives: list, frames: list) -> None:
    """Build the dataset in a scratch folder inside ``out``, then swap it in: never half-written."""
    out.mkdir(parents=True, exist_ok=True)
    scratch = Path(tempfile.mkdtemp(prefix=".synth.", dir=out))
    try:
        write_dataset(scratch, positives, negatives, frames)
        for part in ("crops", "frames"):
            if (out / part).exists():
                shutil.rmtree(out / part)
            (scratch / part).rename(out / part)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


def write_dataset(root: str | Path, positives: list, negatives: list, frames: list) -> None:
    rows = []
    for folder, crops in (("pos", positives), ("neg", negatives)):
        for i, crop in enumerate(crops):
            name = "%s/%05d.png" % (folder, i)
            _write_png(root / "crops" / name, crop.image)
            rows.append((name, folder, crop.category))
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(CROPS_HEADER)
    writer.writerows(rows)
    fileio.write_text(root / "crops" / "crops.csv", buf.getvalue())
    boxes = []
    for i, frame in enumerate(frames):
        name = "%05d.png" % i
        _write_png(root / "frames" / name, frame.image)
        boxes += [Box(name, u, v, w, h, label) for u, v, w, h, label in frame.boxes] or [Box(name, 0, 0, 0, 0, "")]
    (root / "frames").mkdir(parents=True, exist_ok=True)
    fileio.write_text(root / "frames" / "boxes.csv", format_boxes(boxes))


def _write_png(path, image):
    ok, data = cv2.imencode(".png", image, [cv2.IMWRITE_PNG_COMPRESSION, 6])
    if not ok:
        raise ForaNavError("%s: cannot encode PNG" % path)
    fileio.write_bytes(path, data.tobytes())
