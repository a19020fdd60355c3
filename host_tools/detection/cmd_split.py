"""Split annotated imagery into a training and a held-out part (seeded), one boxes CSV per source.

Example: foranav split --data ../shared/data/real/*/boxes.csv --by group --held-out 0.25 --seed 0 --out runs/split
writes OUT/train/<source>/boxes.csv and OUT/test/<source>/boxes.csv (<source>: the CSV's folder name), whose
image paths point back to the original images (nothing is copied). Every image of a source goes to one side
only; a source of n >= 2 images (or groups) holds back at least one. Images listed with no boxes stay with
their source. --by group holds back whole groups: the images of one flight, block or region look alike, so a
split by image scores the detector on the places it learnt. A group is the region in a tiles.csv beside the
CSV (columns image,region,tile_y0,tile_x0,width,height), else the image's folder and the first '_'-separated
word of its name (Stand_01.jpg -> Stand); a source of one group is split by image. Tiles that overlap a
held-out tile of their region (a tiles.csv says where each lies) leave the training side: one crown is never
on both sides.
"""
import argparse
import csv
import os
from collections.abc import Sequence
from pathlib import Path, PurePosixPath

import numpy as np

from host_tools import annotations, argtypes, fileio
from host_tools.errors import ForaNavError

SPLIT_UNITS = ("image", "group")
TILES_CSV = "tiles.csv"
TILES_HEADER = ("image", "region", "tile_y0", "tile_x0", "width", "height")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--data", nargs="+", action="extend", default=[], required=True, metavar="CSV",
                        help="boxes CSVs (one source each; repeat or list several)")
    parser.add_argument("--by", choices=SPLIT_UNITS, default="image",
                        help="hold out whole images or whole groups (region in a tiles.csv beside the CSV, else "
                        "folder and name prefix); default %(default)s")
    parser.add_argument("--held-out", type=argtypes.float_range(0.0, 1.0), default=0.25, metavar="FRACTION",
                        help="share of each source's images (or groups) held out (default %(default)s)")
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


def name_group(image: str) -> str:
    """An image's group by name: its folder and the first '_'-separated word of its file name."""
    path = PurePosixPath(image.replace("\\", "/"))
    return str(path.parent / path.stem.split("_")[0])


def read_tiles(csv_path: Path) -> dict[str, tuple[str, int, int, int, int]]:
    """{image file name: (region, y0, x0, height, width)} of the tiles.csv beside a boxes CSV ({} without one)."""
    path = csv_path.parent / TILES_CSV
    if not path.is_file():
        return {}
    rows = annotations.read_csv_rows(path, "tiles CSV")
    if not rows or tuple(h.strip() for h in rows[0]) != TILES_HEADER:
        raise ForaNavError("%s: header must be %s" % (path, ",".join(TILES_HEADER)))
    tiles = {}
    for line_no, row in enumerate(rows[1:], start=2):
        if not row:
            continue
        try:
            y0, x0, width, height = (int(v) for v in row[2:6])
        except ValueError:
            raise ForaNavError("%s: line %d: tile_y0, tile_x0, width and height must be integers" % (path, line_no))
        if len(row) != len(TILES_HEADER) or width <= 0 or height <= 0:
            raise ForaNavError("%s: line %d: expected %s with a positive size"
                               % (path, line_no, ",".join(TILES_HEADER)))
        tiles[PurePosixPath(row[0]).name] = (row[1].strip(), y0, x0, height, width)
    return tiles


def image_groups(images: Sequence[str], tiles: dict) -> dict[str, str]:
    """{image: group}: its tile's region when the tiles.csv lists it, else name_group."""
    out = {}
    for image in images:
        tile = tiles.get(PurePosixPath(image).name)
        out[image] = "region %s" % tile[0] if tile else name_group(image)
    return out


def split_by_group(images: Sequence[str], groups: dict[str, str], held_out: float,
                   rng: np.random.RandomState) -> tuple[list[str], list[str]]:
    """(train images, test images): whole groups held out (a source of one group: by image)."""
    names = list(dict.fromkeys(groups[im] for im in images))
    if len(names) < 2:
        return split_images(images, held_out, rng)
    _train_groups, test_groups = split_images(names, held_out, rng)
    test = set(test_groups)
    return [im for im in images if groups[im] not in test], [im for im in images if groups[im] in test]


def overlapping(train: Sequence[str], test: Sequence[str], tiles: dict) -> list[str]:
    """Training tiles that share pixels with a held-out tile of the same region (both listed in tiles)."""
    held = [tiles[PurePosixPath(im).name] for im in test if PurePosixPath(im).name in tiles]
    out = []
    for image in train:
        tile = tiles.get(PurePosixPath(image).name)
        if tile and any(_overlap(tile, other) for other in held):
            out.append(image)
    return out


def _overlap(a, b) -> bool:
    region_a, ya, xa, ha, wa = a
    region_b, yb, xb, hb, wb = b
    return region_a == region_b and ya < yb + hb and yb < ya + ha and xa < xb + wb and xb < xa + wa


def _listed(names: Sequence[str], shown: int = 4) -> str:
    return ", ".join(names[:shown]) + (" and %d more" % (len(names) - shown) if len(names) > shown else "")


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
        images = list(annotations.boxes_by_image(boxes))
        tiles = read_tiles(Path(csv_path))
        if args.by == "group":
            groups = image_groups(images, tiles)
            train, test = split_by_group(images, groups, args.held_out, rng)
        else:
            groups = {}
            train, test = split_images(images, args.held_out, rng)
        dropped = overlapping(train, test, tiles)
        train = [im for im in train if im not in set(dropped)]
        plans.append((csv_path, name, boxes, train, test, dropped, groups))
    for csv_path, name, boxes, train, test, dropped, groups in plans:
        source = Path(csv_path).resolve().parent
        for side, images in (("train", train), ("test", test)):
            target = out / side / name
            keep = set(images)
            rows = [annotations.Box(os.path.relpath(str(source / b.image), str(target.resolve())), b.x_center,
                                    b.y_center, b.width, b.height, b.label) for b in boxes if b.image in keep]
            if rows:
                annotations.write_boxes(target / "boxes.csv", rows)
        held_groups = sorted(set(groups[im] for im in test)) if len(set(groups.values())) > 1 else []
        print("%s: %d images to train, %d held out%s%s" % (
            name, len(train), len(test), " (groups %s)" % _listed(held_groups) if held_groups else "",
            "; %d training tiles overlapping a held-out tile left out" % len(dropped) if dropped else ""))
    return 0
