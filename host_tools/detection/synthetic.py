"""Small, self-contained synthetic scenes for the detector's tests and benchmark.

Not the plantation simulator (host_tools.sim renders the real training data): just enough structure to
exercise the detector without it. A "palm" is a dark under-canopy disc with a star of fronds carrying
fine, high-contrast leaflets; a "roof" is a grey rectangle with a ridge and tile lines; the ground is
brown noise. Everything is drawn from a seed.
"""
import math
from collections.abc import Iterable

import cv2
import numpy as np

from host_tools.annotations import Box
from host_tools.detection import dataset, training

from foranav_model import TreeModel

GROUND_BGR = (70, 100, 125)


def ground(rng: np.random.RandomState, height: int, width: int) -> np.ndarray:
    base = np.empty((height, width, 3), np.float32)
    base[:] = GROUND_BGR
    noise = cv2.resize(rng.normal(0, 12, (height // 8 + 1, width // 8 + 1)).astype(np.float32), (width, height))
    fine = rng.normal(0, 6, (height, width)).astype(np.float32)
    base += (noise + fine)[..., None]
    return np.clip(base, 0, 255).astype(np.uint8)


def draw_palm(image: np.ndarray, rng: np.random.RandomState, cx: float, cy: float, diameter: float) -> None:
    """A star-shaped crown of `diameter` pixels centred at (cx, cy), drawn in place."""
    radius = diameter / 2.0
    cv2.circle(image, (int(round(cx)), int(round(cy))), int(radius * 0.5), (20, 45, 30), -1, cv2.LINE_AA)
    fronds = rng.randint(14, 19)
    start = rng.uniform(0, 2 * math.pi)
    for i in range(fronds):
        angle = start + 2 * math.pi * i / fronds + rng.normal(0, 0.08)
        length = radius * rng.uniform(0.85, 1.0)
        tip = (cx + length * math.cos(angle), cy + length * math.sin(angle))
        cv2.line(image, _pt(cx, cy), _pt(*tip), (50, 150, 150), max(1, int(diameter * 0.012)), cv2.LINE_AA)
        for t in np.arange(0.15, 0.95, 0.05):
            px, py = cx + t * length * math.cos(angle), cy + t * length * math.sin(angle)
            for side in (-1, 1):
                leaf_angle = angle + side * math.radians(50)
                leaf = 0.22 * length * (1.0 - 0.6 * t)
                end = (px + leaf * math.cos(leaf_angle), py + leaf * math.sin(leaf_angle))
                colour = (35 + rng.randint(0, 25), 150 + rng.randint(0, 50), 95 + rng.randint(0, 50))
                cv2.line(image, _pt(px, py), _pt(*end), colour, 1, cv2.LINE_AA)


def draw_roof(image: np.ndarray, rng: np.random.RandomState, cx: float, cy: float, size: float) -> None:
    """A grey gabled roof, size pixels across, drawn in place."""
    half = size / 2.0
    x0, y0, x1, y1 = _pt(cx - half, cy - half * 0.7), (0, 0), (0, 0), _pt(cx + half, cy + half * 0.7)
    cv2.rectangle(image, x0, y1, (150, 150, 155), -1)
    cv2.line(image, _pt(cx - half, cy), _pt(cx + half, cy), (90, 90, 95), 2)
    for x in np.arange(cx - half, cx + half, max(3.0, size / 12.0)):
        cv2.line(image, _pt(x, cy - half * 0.7), _pt(x, cy + half * 0.7), (120, 120, 128), 1)
    del y0, x1


def scene(seed: int, width: int = 352, height: int = 288, palms: int = 2, roofs: int = 1,
          diameter: tuple[float, float] = (80, 110), margin: float | None = None) -> tuple[np.ndarray, list, list]:
    """(BGR image, [(cx, cy, diameter) of palms], [(cx, cy, size) of roofs]); palms lie wholly in frame."""
    rng = np.random.RandomState(seed)
    image = ground(rng, height, width)
    placed = []
    palms_out, roofs_out = [], []
    for kind, count in (("roof", roofs), ("palm", palms)):
        for _ in range(count):
            for _attempt in range(50):
                size = rng.uniform(*diameter)
                edge = size / 2.0 + (margin if margin is not None else 2.0)
                if width <= 2 * edge or height <= 2 * edge:
                    break
                cx, cy = rng.uniform(edge, width - edge), rng.uniform(edge, height - edge)
                if all(math.hypot(cx - px, cy - py) > (size + ps) / 2.0 for px, py, ps in placed):
                    placed.append((cx, cy, size))
                    if kind == "palm":
                        draw_palm(image, rng, cx, cy, size)
                        palms_out.append((cx, cy, size))
                    else:
                        draw_roof(image, rng, cx, cy, size)
                        roofs_out.append((cx, cy, size))
                    break
    return image, palms_out, roofs_out


def _pt(x: float, y: float) -> tuple[int, int]:
    return int(round(x)), int(round(y))


def annotated_frames(seeds: Iterable[int], width: int = 352, height: int = 288,
                     diameter: tuple[float, float] = (65, 130)) -> list[dataset.Frame]:
    """host_tools.detection.dataset.Frame objects of synthetic scenes (palms labelled oil_palm, roofs roof)."""
    frames = []
    for seed in seeds:
        image, palms, roofs = scene(seed, width, height, palms=2, roofs=1, diameter=diameter)
        boxes = [Box("%d.png" % seed, cx, cy, d, d, "oil_palm") for cx, cy, d in palms]
        boxes += [Box("%d.png" % seed, cx, cy, d, d * 0.7, "roof") for cx, cy, d in roofs]
        frames.append(dataset.Frame("%d.png" % seed, image, boxes))
    return frames


def small_model(seed: int = 1, frames: int = 30) -> TreeModel:
    """A detector model trained on synthetic scenes in about a second (for tests; not a shipped model)."""
    return training.train(annotated_frames(range(1000 + seed, 1000 + seed + frames)), "oil_palm", seed=seed)
