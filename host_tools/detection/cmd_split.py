"""Split annotated imagery by image into a training and a held-out part (seeded), one boxes CSV per source.

Example: foranav split --data ../shared/data/real/*/boxes.csv --held-out 0.25 --seed 0 --out runs/real_split
writes OUT/train/<source>/boxes.csv and OUT/test/<source>/boxes.csv (<source>: the CSV's folder name), whose
image paths point back to the original images (nothing is copied). Every image of a source goes to one side
only; a source of n >= 2 images holds back at least one. Images listed with no boxes stay with their source.
"""
import argparse
import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from host_tools import annotations, argtypes, fileio
from host_tools.errors import ForaNavError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--data", nargs="+", action="extend", default=[], required=True, metavar="CSV",
                        help="boxes CSVs (one source each; repeat or list several)")
    parser.add_argument("--held-out", type=argtypes.float_range(0.0, 1.0), default=0.25, metavar="FRACTION",
                        help="share of each source's images held out (default %(default)s)")
    parser.add_argument("--seed", type=argtypes.seed, default=0, help="seed of the split (default 0)")
    parser.add_argument("--out", required=True, metavar="DIR", help="folder for train/ and test/")


def split_images(images: Sequence[str], held_out: float,
                 rng: np.random.RandomState) -> tuple[list[str], list[str]]:
    """(train images, test images) of one source, each in the source's order."""
    order = rng.permutation(len(images))
    count = int(round(held_out * len(images)))
    if len(images) >= 2:
        count = min(max(1, count), len(images) - 1)
    test = set(order[:count].tolist())
    return ([im for i, im in enumerate(images) if i not in test], [im for i, im in enumerate(images) if i in test])


def run(args: argparse.Namespace) -> int:
    if not 0.0 < args.held_out < 1.0:
        raise ForaNavError("--held-out must be between 0 and 1")
    fileio.check_output_dir(args.out, "--out")
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise ForaNavError("--out %s: not a folder" % out)
    rng = np.random.RandomState(args.seed)
    names = [Path(p).resolve().parent.name for p in args.data]
    if len(set(names)) != len(names):
        raise ForaNavError("--data: two CSVs share the folder name %s" % sorted(n for n in names if names.count(n) > 1)[0])
    plans = []
    for csv_path, name in zip(args.data, names):
        boxes = annotations.read_boxes(csv_path)
        by_image = annotations.boxes_by_image(boxes)
        train, test = split_images(list(by_image), args.held_out, rng)
        plans.append((csv_path, name, boxes, train, test))
    for csv_path, name, boxes, train, test in plans:
        source = Path(csv_path).resolve().parent
        for side, images in (("train", train), ("test", test)):
            target = out / side / name
            keep = set(images)
            rows = [annotations.Box(os.path.relpath(str(source / b.image), str(target.resolve())), b.x_center,
                                    b.y_center, b.width, b.height, b.label) for b in boxes if b.image in keep]
            if rows:
                annotations.write_boxes(target / "boxes.csv", rows)
        print("%s: %d images to train, %d held out" % (name, len(train), len(test)))
    return 0
