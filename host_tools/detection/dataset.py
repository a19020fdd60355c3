"""Annotated frames for training and evaluation, and the windows cut from them.

A frame comes from a boxes CSV (host_tools.annotations). A tree is *complete* when its box lies wholly
inside the frame; only complete trees of the species are positives (the paper's negatives "do not contain
complete trees"). Windows are square, W = crown size x margin, given by centre and side in frame pixels.
"""
import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from host_tools import annotations, images
from host_tools.annotations import Box
from host_tools.errors import ForaNavError

import foranav_detector as detector_core
import foranav_features as features

EDGE_TOLERANCE_PX = 0.5  # a box this close to the frame edge is taken as cut by it


@dataclass
class Frame:
    path: str
    bgr: np.ndarray
    boxes: list
    hsv: np.ndarray = field(init=False, repr=False)
    value: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self.hsv = features.bgr_to_hsv(self.bgr)
        self.value = cv2.extractChannel(self.hsv, 2)

    @property
    def width(self) -> int:
        return self.bgr.shape[1]

    @property
    def height(self) -> int:
        return self.bgr.shape[0]

    def complete(self, box: Box) -> bool:
        x0, y0, x1, y1 = box.corners()
        return (x0 >= -EDGE_TOLERANCE_PX + 1 and y0 >= -EDGE_TOLERANCE_PX + 1
                and x1 <= self.width - 1 + EDGE_TOLERANCE_PX and y1 <= self.height - 1 + EDGE_TOLERANCE_PX)

    def trees(self, species: str) -> list[Box]:
        """Complete boxes of the species."""
        return [b for b in self.boxes if b.label == species and self.complete(b)]

    def window_fits(self, cx: float, cy: float, side: float) -> bool:
        return side / 2.0 <= cx <= self.width - side / 2.0 and side / 2.0 <= cy <= self.height - side / 2.0

    def typical_crown(self) -> float:
        """Median crown size (px) of the frame's labelled boxes (0 without any): what a user gives as --crown-px."""
        sizes = [crown_size(b) for b in self.boxes if b.label]
        return float(np.median(sizes)) if sizes else 0.0

    def annotated_area(self) -> np.ndarray | None:
        """The convex hull (float32 polygon) of the labelled boxes grown by half a typical crown, or None.

        Survey sites often annotate one block: what lies outside the hull is neither tree nor background."""
        if not hasattr(self, "_area"):
            grow = 0.5 * self.typical_crown()
            corners = [(x, y) for b in self.boxes if b.label
                       for x in (b.x_center - b.width / 2 - grow, b.x_center + b.width / 2 + grow)
                       for y in (b.y_center - b.height / 2 - grow, b.y_center + b.height / 2 + grow)]
            self._area = cv2.convexHull(np.array(corners, np.float32)) if corners else None
        return self._area

    def in_area(self, x: float, y: float) -> bool:
        area = self.annotated_area()
        return area is not None and cv2.pointPolygonTest(area, (float(x), float(y)), False) >= 0


def read_image(path: str | os.PathLike) -> np.ndarray:
    return images.read_image(path)  # checked header: no huge allocations, truncated files refused


def read_frame(path: str | os.PathLike, where: str = "") -> np.ndarray:
    """An image the detector scans whole: also at least one HOG window (24 px) on its shorter side."""
    bgr = read_image(path)
    if min(bgr.shape[:2]) < features.HOG_WINDOW:
        raise ForaNavError("%s%s: a %dx%d px image; the detector's smallest window needs %d px on each side"
                           % (where, path, bgr.shape[1], bgr.shape[0], features.HOG_WINDOW))
    return bgr


def load_frames(csv_paths: Sequence[str | os.PathLike], limit: int | None = None,
                frame_done: Callable[[], None] = lambda: None) -> list[Frame]:
    """Frames of one or more boxes CSVs (image paths relative to each CSV), in file order."""
    frames = []
    for csv_path in csv_paths:
        csv_path = Path(csv_path)
        for image, boxes in annotations.boxes_by_image(annotations.read_boxes(csv_path)).items():
            frames.append(Frame(str(csv_path.parent / image), read_frame(csv_path.parent / image, "%s: " % csv_path),
                                boxes))
            frame_done()
            if limit is not None and len(frames) >= limit:
                return frames
    if not frames:
        raise ForaNavError("no frames in %s" % ", ".join(str(p) for p in csv_paths))
    return frames


def crown_size(box: Box) -> float:
    return max(box.width, box.height)


def is_tree_window(frame: Frame, species: str, cx: float, cy: float, side: float, margin: float,
                   centre_tolerance: float = 0.25, size_tolerance: float = 1.4) -> bool:
    """Does this window frame a complete tree of the species well enough to count as a detection of it?"""
    for box in frame.trees(species):
        expected = crown_size(box) * margin
        if (math.hypot(box.x_center - cx, box.y_center - cy) <= centre_tolerance * side
                and 1.0 / size_tolerance <= side / expected <= size_tolerance):
            return True
    return False


def tree_window_mask(frame: Frame, species: str, cx: np.ndarray, cy: np.ndarray, side: float, margin: float,
                     centre_tolerance: float = 0.25, size_tolerance: float = 1.4) -> np.ndarray:
    """is_tree_window for arrays of window centres cx, cy (one side): a boolean array."""
    cx, cy = np.asarray(cx, np.float64), np.asarray(cy, np.float64)
    out = np.zeros(cx.shape, bool)
    for box in frame.trees(species):
        expected = crown_size(box) * margin
        if 1.0 / size_tolerance <= side / expected <= size_tolerance:
            out |= np.hypot(box.x_center - cx, box.y_center - cy) <= centre_tolerance * side
    return out


def near_any_tree(frame: Frame, cx: float, cy: float, side: float) -> bool:
    """Is a tree (any label, complete or not) centred inside this window? (not usable as background)"""
    half = side / 2.0
    return any(abs(b.x_center - cx) < half and abs(b.y_center - cy) < half for b in frame.boxes
               if b.label and b.label != "")


def top_descriptor(frame: Frame, cx: float, cy: float, side: float, transform: int = 0) -> np.ndarray:
    """Top-layer descriptor of a window; transform 0..7 = rot90 count (0-3) and optional mirror (+4)."""
    small = features.window_with_context(frame.value, cx - side / 2.0, cy - side / 2.0, side)
    if transform % 4:
        small = np.rot90(small, transform % 4)
    if transform >= 4:
        small = small[:, ::-1]
    return features.top_layer_hog(np.ascontiguousarray(small))


def pixel_window(frame: Frame, cx: float, cy: float, side: int) -> tuple[slice, slice]:
    """Integer slices (rows, cols) of a window clipped to the frame (the detector's window clamp)."""
    x0, y0, side = detector_core.window_in_frame(cx, cy, side, frame.height, frame.width)
    return slice(y0, y0 + side), slice(x0, x0 + side)
