"""Sprites: a top-down drawing of one tree or object with its coverage, composited onto the orthomosaic.

Every renderer draws with OpenCV primitives at sub-pixel precision (fixed-point ``shift``) into a square canvas
whose colour is premultiplied by coverage (drawn on black) and a coverage mask drawn with the same primitives.
Positions are continuous pixel coordinates of the canvas: (0, 0) is the top-left corner of the top-left pixel.
"""
import math
from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np

Colour = Sequence[float]  # (b, g, r), 0-255

SHIFT = 4  # fixed-point bits for sub-pixel drawing
_ONE = 1 << SHIFT
AA = cv2.LINE_AA


@dataclass
class Sprite:
    premultiplied: np.ndarray  # HxWx3 float32, colour * coverage
    alpha: np.ndarray  # HxW float32 in [0, 1]
    origin: tuple  # (col, row) of the canvas's top-left pixel in the target image


class Canvas:
    """Colour + coverage drawn together; coordinates are continuous canvas pixels (float)."""

    def __init__(self, size: int):
        self.size = int(size)
        self.colour = np.zeros((self.size, self.size, 3), np.uint8)
        self.mask = np.zeros((self.size, self.size), np.uint8)

    def polylines(self, polylines: Sequence[np.ndarray], colour: Colour, thickness: int = 1,
                  closed: bool = False) -> None:
        """Draw open polylines: a list of (N, 2) float arrays of (x, y) points."""
        if not len(polylines):
            return
        pts = [_fixed(p) for p in polylines]
        cv2.polylines(self.colour, pts, closed, _bgr(colour), int(thickness), AA, SHIFT)
        cv2.polylines(self.mask, pts, closed, 255, int(thickness), AA, SHIFT)

    def segments(self, starts: np.ndarray, ends: np.ndarray, colour: Colour, thickness: int = 1) -> None:
        """Draw many straight segments (arrays of shape (N, 2)) in one colour."""
        if len(starts) == 0:
            return
        pairs = np.stack([starts, ends], axis=1)  # (N, 2, 2)
        self.polylines(list(pairs), colour, thickness)

    def polygon(self, points: np.ndarray, colour: Colour) -> None:
        pts = _fixed(points)
        cv2.fillPoly(self.colour, [pts], _bgr(colour), AA, SHIFT)
        cv2.fillPoly(self.mask, [pts], 255, AA, SHIFT)

    def circle(self, centre: Sequence[float], radius: float, colour: Colour) -> None:
        c = tuple(int(v) for v in np.round(np.asarray(centre) * _ONE))
        cv2.circle(self.colour, c, int(round(radius * _ONE)), _bgr(colour), -1, AA, SHIFT)
        cv2.circle(self.mask, c, int(round(radius * _ONE)), 255, -1, AA, SHIFT)

    def ellipse(self, centre: Sequence[float], axes: Sequence[float], angle_deg: float, colour: Colour) -> None:
        c = tuple(int(v) for v in np.round(np.asarray(centre) * _ONE))
        a = tuple(max(1, int(round(v * _ONE))) for v in axes)
        cv2.ellipse(self.colour, c, a, float(angle_deg), 0, 360, _bgr(colour), -1, AA, SHIFT)
        cv2.ellipse(self.mask, c, a, float(angle_deg), 0, 360, 255, -1, AA, SHIFT)

    def to_sprite(self, origin: tuple[int, int], blur_sigma: float = 0.0,
                  shading: np.ndarray | None = None) -> Sprite:
        """Finish: optional softening blur and a multiplicative shading field (HxW), as a Sprite."""
        alpha = self.mask.astype(np.float32) * (1.0 / 255.0)
        colour = self.colour.astype(np.float32)
        if shading is not None:
            colour *= shading[..., None]
        if blur_sigma > 0:
            colour = cv2.GaussianBlur(colour, (0, 0), blur_sigma)
            alpha = cv2.GaussianBlur(alpha, (0, 0), blur_sigma)
        # colours were drawn opaque over black with anti-aliased edges, so they are already premultiplied by
        # the coverage that the mask holds
        return Sprite(colour, np.clip(alpha, 0.0, 1.0), origin)


def canvas_for(centre_col: float, centre_row: float, diameter_px: float,
               pad: int = 3) -> tuple[Canvas, np.ndarray, tuple[int, int]]:
    """A canvas big enough for a crown of diameter_px centred at a continuous image position.

    Returns (canvas, centre_in_canvas, origin) where origin is the integer image pixel of canvas (0, 0).
    """
    half = int(math.ceil(diameter_px / 2.0)) + pad
    origin = (int(math.floor(centre_col)) - half, int(math.floor(centre_row)) - half)
    centre = (centre_col - origin[0], centre_row - origin[1])
    return Canvas(2 * half + 1), np.array(centre, dtype=float), origin


def composite(image: np.ndarray, sprite: Sprite) -> None:
    """Alpha-composite a sprite onto a float32 HxWx3 image in place (clipped at the image border)."""
    h, w = image.shape[:2]
    ox, oy = sprite.origin
    sh, sw = sprite.alpha.shape
    x0, y0, x1, y1 = max(ox, 0), max(oy, 0), min(ox + sw, w), min(oy + sh, h)
    if x0 >= x1 or y0 >= y1:
        return
    a = sprite.alpha[y0 - oy:y1 - oy, x0 - ox:x1 - ox, None]
    p = sprite.premultiplied[y0 - oy:y1 - oy, x0 - ox:x1 - ox]
    region = image[y0:y1, x0:x1]
    region *= (1.0 - a)
    region += p


def darken(image: np.ndarray, mask: np.ndarray, origin: tuple[int, int], strength: float) -> None:
    """Multiply an image region by (1 - strength * mask): cast shadows."""
    h, w = image.shape[:2]
    ox, oy = origin
    sh, sw = mask.shape
    x0, y0, x1, y1 = max(ox, 0), max(oy, 0), min(ox + sw, w), min(oy + sh, h)
    if x0 >= x1 or y0 >= y1:
        return
    m = mask[y0 - oy:y1 - oy, x0 - ox:x1 - ox, None]
    image[y0:y1, x0:x1] *= (1.0 - strength * m)


def radial_shading(size: int, centre: np.ndarray, radius: float, sun_dir: Sequence[float],
                   strength: float) -> np.ndarray:
    """Brighter on the sun side, darker on the far side: 1 + strength * (p - c) . sun / radius."""
    ys, xs = np.mgrid[0:size, 0:size].astype(np.float32) + 0.5
    d = ((xs - centre[0]) * sun_dir[0] + (ys - centre[1]) * sun_dir[1]) / max(radius, 1e-6)
    return (1.0 + strength * np.clip(d, -1.0, 1.0)).astype(np.float32)


def _fixed(points: np.ndarray) -> np.ndarray:
    return np.round(np.asarray(points, dtype=float) * _ONE).astype(np.int32).reshape(-1, 1, 2)


def _bgr(colour: Colour) -> tuple[int, int, int]:
    return tuple(int(max(0, min(255, round(c)))) for c in colour)
