"""Box annotations: the one CSV format for real and rendered data.

Same format as ``shared/data/real/*/boxes.csv``: one row per annotated tree, in pixels of the original image
(origin top-left, x right, y down, axis-aligned boxes)::

    image,x_center,y_center,width,height,label

``image`` is relative to the CSV's folder. An image with no trees (a pure negative frame) is listed with an
empty label and zero-size box so that it is still part of the data set.

``read_boxes`` refuses, naming the file and line: NUL bytes (a binary file, or one cut by a crash, is not CSV
text), a header other than the one above, a row without six fields, box fields that are not finite numbers,
a negative size, a centre or size beyond ``MAX_BOX_PX`` (no image we read is that large:
host_tools.images.MAX_IMAGE_PIXELS) and a box listed twice for the same image (a duplicated row would count
one tree twice in training and evaluation).
"""
import csv
import io
import math
import os
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

from host_tools.errors import ForaNavError
from host_tools import fileio

HEADER = ("image", "x_center", "y_center", "width", "height", "label")
MIN_BOX_PX = 1.0  # a labelled box smaller than one pixel marks nothing (and divides by zero downstream)
MAX_BOX_PX = 65536.0  # a centre or size beyond this many pixels is no box of an image we can read


@dataclass(frozen=True)
class Box:
    image: str  # relative to the CSV's folder
    x_center: float
    y_center: float
    width: float
    height: float
    label: str

    @property
    def is_empty_marker(self) -> bool:
        return self.label == ""

    def corners(self) -> tuple[float, float, float, float]:
        """(x0, y0, x1, y1) in pixels."""
        return (self.x_center - self.width / 2, self.y_center - self.height / 2,
                self.x_center + self.width / 2, self.y_center + self.height / 2)


def read_boxes(csv_path: str | os.PathLike) -> list[Box]:
    """Read a boxes CSV; raises ForaNavError naming the file and line on bad input (module docstring)."""
    csv_path = Path(csv_path)
    rows = read_csv_rows(csv_path, "boxes CSV")
    if not rows:
        raise ForaNavError("%s: empty CSV (expected header %s)" % (csv_path, ",".join(HEADER)))
    if tuple(h.strip() for h in rows[0]) != HEADER:
        raise ForaNavError("%s: header must be %s" % (csv_path, ",".join(HEADER)))
    boxes, first_line = [], {}
    for line_no, row in enumerate(rows[1:], start=2):
        if not row:
            continue
        box = _box(csv_path, line_no, row)
        key = (box.image, box.x_center, box.y_center, box.width, box.height)
        if key in first_line:
            raise ForaNavError("%s: line %d: the same box of %s as line %d (a duplicated row)"
                               % (csv_path, line_no, box.image, first_line[key]))
        first_line[key] = line_no
        boxes.append(box)
    if not boxes:
        raise ForaNavError("%s: no rows" % csv_path)
    return boxes


def read_csv_rows(csv_path: str | os.PathLike, what: str) -> list[list[str]]:
    """The rows of a CSV file; ForaNavError naming the file (``what`` it should be) when it is missing,
    unreadable, holds NUL bytes or is not CSV."""
    text = fileio.read_text(csv_path, what)
    refuse_nul_bytes(text, csv_path)
    try:
        return list(csv.reader(io.StringIO(text)))
    except csv.Error as err:  # e.g. a field over csv.field_size_limit() (128 KiB)
        raise ForaNavError("%s: not a valid CSV: %s" % (csv_path, err))


def refuse_nul_bytes(text: str, csv_path: str | os.PathLike) -> None:
    """ForaNavError naming the line of the first NUL byte: a binary file, or one cut by a crash, is no CSV."""
    if "\x00" in text:
        line_no = text.count("\n", 0, text.index("\x00")) + 1
        raise ForaNavError("%s: line %d: NUL bytes, not CSV text" % (csv_path, line_no))


def _box(csv_path, line_no, row):
    if len(row) != len(HEADER):
        raise ForaNavError("%s: line %d: expected %d fields, got %d" % (csv_path, line_no, len(HEADER), len(row)))
    try:
        values = [float(v) for v in row[1:5]]
    except ValueError:
        raise ForaNavError("%s: line %d: box fields must be numbers" % (csv_path, line_no))
    if not all(math.isfinite(v) for v in values) or values[2] < 0 or values[3] < 0:
        raise ForaNavError("%s: line %d: box must be finite with non-negative size" % (csv_path, line_no))
    label = row[5].strip()
    if label and min(values[2], values[3]) < MIN_BOX_PX:  # an unlabelled row marks an image with no trees
        raise ForaNavError("%s: line %d: a %g x %g px box of %s; a labelled box is at least %d px wide and high"
                           % (csv_path, line_no, values[2], values[3], label, MIN_BOX_PX))
    for name, value in zip(HEADER[1:5], values):
        if abs(value) > MAX_BOX_PX:
            raise ForaNavError("%s: line %d: %s %g px is beyond any image (at most %d px)"
                               % (csv_path, line_no, name, value, MAX_BOX_PX))
    return Box(row[0], *values, label)


def boxes_by_image(boxes: Iterable[Box]) -> dict[str, list[Box]]:
    """{image: [Box, ...]} in first-seen order; images listed only by an empty marker map to []."""
    out = {}
    for b in boxes:
        out.setdefault(b.image, [])
        if not b.is_empty_marker:
            out[b.image].append(b)
    return out


def format_boxes(boxes: Iterable[Box]) -> str:
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(HEADER)
    for b in boxes:
        writer.writerow([b.image, _num(b.x_center), _num(b.y_center), _num(b.width), _num(b.height), b.label])
    return buf.getvalue()


def write_boxes(csv_path: str | os.PathLike, boxes: Iterable[Box]) -> None:
    fileio.write_text(csv_path, format_boxes(boxes))


def _num(v: float) -> str:
    return ("%.2f" % v).rstrip("0").rstrip(".") if v != int(v) else str(int(v))
