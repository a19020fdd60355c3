"""What the host_tools tests share: a small synthetic plantation photograph and its boxes CSV, made at test
time (the real estate photos are never committed; tests that need them are marked realdata)."""
import math
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from host_tools.annotations import Box, write_boxes
from host_tools.sim import ground
from host_tools.sim.sprite import composite
from host_tools.sim.world import render_species

PHOTO_CROWN_PX = 90  # at the default scale (0.35 m crown) 3.9 mm per pixel: the camera's own at 1.25 m


@dataclass(frozen=True)
class SyntheticPhoto:
    photo: Path
    boxes: Path
    centres: np.ndarray  # (N, 2) pixel centres (col, row) of the boxed palms
    heading_deg: float  # row direction in photo pixels, counter-clockwise from photo up
    row_spacing_px: float
    palm_spacing_px: float


def write_synthetic_photo(folder: Path, *, size_px: int = 1000, heading_deg: float = 0.0,
                          palm_spacing_px: float = 115.0, row_spacing_px: float = 160.0, triangular: bool = False,
                          missing: tuple[int, ...] = (), seed: int = 0, name: str = "estate.png") -> SyntheticPhoto:
    """A nadir 'photo' of drawn oil palms in straight rows at a heading (every ``missing`` palm left out),
    written as PNG with its boxes CSV (label oil_palm) beside it."""
    rng = np.random.default_rng(seed)
    image = ground.render_ground(rng, size_px, size_px, 0.0039)
    h = math.radians(heading_deg)
    # photo up = world +x: a direction at heading h is (col, row) = (-sin h, -cos h)
    along = np.array([-math.sin(h), -math.cos(h)])
    across = np.array([-along[1], along[0]])
    centre = np.array([size_px / 2.0, size_px / 2.0])
    centres, index = [], 0
    reach = size_px
    for r in range(-int(reach / row_spacing_px), int(reach / row_spacing_px) + 1):
        shift = palm_spacing_px / 2.0 if triangular and r % 2 else 0.0
        for k in range(-int(reach / palm_spacing_px), int(reach / palm_spacing_px) + 1):
            p = centre + across * r * row_spacing_px + along * (k * palm_spacing_px + shift)
            half = PHOTO_CROWN_PX / 2.0
            if not (half <= p[0] <= size_px - half and half <= p[1] <= size_px - half):
                continue
            index += 1
            if index in missing:
                continue
            centres.append(p)
    for col, row in centres:
        composite(image, render_species("oil_palm", rng, float(col), float(row), PHOTO_CROWN_PX))
    photo = Path(folder) / name
    cv2.imwrite(str(photo), np.clip(image + 0.5, 0, 255).astype(np.uint8))
    boxes = Path(folder) / "boxes.csv"
    write_boxes(boxes, [Box(name, round(float(c), 2), round(float(r), 2), PHOTO_CROWN_PX, PHOTO_CROWN_PX, "oil_palm")
                        for c, r in centres])
    return SyntheticPhoto(photo, boxes, np.array(centres), heading_deg, row_spacing_px, palm_spacing_px)
