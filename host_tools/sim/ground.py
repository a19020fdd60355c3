"""The ground under the trees: grass and soil patches, weeds and pebbles. Rendered once per world."""
import cv2
import numpy as np

GRASS = np.array((60, 120, 95), np.float32)
DRY_GRASS = np.array((75, 135, 140), np.float32)
SOIL = np.array((70, 100, 125), np.float32)
WEED_COLOURS = ((45, 130, 80), (35, 95, 60), (90, 160, 140), (60, 80, 95))
BAND_ROWS = 256


def value_noise(rng: np.random.Generator, height: int, width: int, cells: int) -> np.ndarray:
    """Smooth noise in [0, 1]: a coarse random grid, interpolated up (cells = features across the width)."""
    cells_w = max(2, int(cells))
    cells_h = max(2, int(round(cells * height / max(width, 1))))
    coarse = rng.random((cells_h + 3, cells_w + 3)).astype(np.float32)
    fine = cv2.resize(coarse, (width, height), interpolation=cv2.INTER_CUBIC)
    return np.clip(fine, 0.0, 1.0)


def render_ground(rng: np.random.Generator, height: int, width: int, metres_per_pixel: float,
                  light: float = 1.0) -> np.ndarray:
    """HxWx3 float32 BGR ground; feature sizes are in metres so it looks the same at any pixel scale.

    The colour field has no detail finer than a few centimetres, so it is computed at a quarter of the
    resolution and interpolated up once; only the weed strokes are drawn at full resolution.
    """
    small_h, small_w = max(2, height // 4), max(2, width // 4)
    extent_m = width * metres_per_pixel
    soil_mix = np.clip((value_noise(rng, small_h, small_w, extent_m / 0.8) - 0.45) * 2.5, 0.0, 1.0)
    dry_mix = value_noise(rng, small_h, small_w, extent_m / 0.4)
    grass = GRASS + (DRY_GRASS - GRASS) * dry_mix[..., None]
    small = grass + (SOIL - grass) * soil_mix[..., None]
    mottle = 0.85 + 0.3 * value_noise(rng, small_h, small_w, extent_m / 0.05)
    small *= (mottle * light)[..., None]
    image = cv2.resize(small, (width, height), interpolation=cv2.INTER_LINEAR)
    _scatter_strokes(image, rng, metres_per_pixel, density_per_m2=900, length_m=0.012, light=light)
    return image


def _scatter_strokes(image, rng, mpp, density_per_m2, length_m, light=1.0):
    """Short weed blades and twigs: thin strokes in random directions."""
    height, width = image.shape[:2]
    n = int(density_per_m2 * height * width * mpp * mpp)
    start = rng.uniform((0, 0), (width, height), size=(n, 2))
    angle = rng.uniform(0, 2 * np.pi, n)
    length = rng.uniform(0.4, 1.0, n) * length_m / mpp
    end = start + length[:, None] * np.stack([np.cos(angle), np.sin(angle)], 1)
    shade = rng.integers(0, len(WEED_COLOURS), n)
    canvas = np.zeros((height, width, 3), np.uint8)
    mask = np.zeros((height, width), np.uint8)
    for i, colour in enumerate(WEED_COLOURS):
        pts = np.round(np.stack([start[shade == i], end[shade == i]], 1) * 16).astype(np.int32)
        cv2.polylines(canvas, list(pts), False, colour, 1, cv2.LINE_AA, 4)
        cv2.polylines(mask, list(pts), False, 255, 1, cv2.LINE_AA, 4)
    # canvas is premultiplied by coverage (drawn on black); blades are 60 % opaque. A band of rows at a time:
    # the same numbers, without full-size float temporaries (a large world's ground is hundreds of MB)
    for rows in row_bands(height):
        alpha = mask[rows].astype(np.float32)[..., None] * (0.6 / 255.0)
        image[rows] *= (1.0 - alpha)
        image[rows] += canvas[rows].astype(np.float32) * (0.6 * light)


def row_bands(height: int, rows_per_band: int = BAND_ROWS) -> list[slice]:
    """Slices of rows covering 0..height, for element-wise work on a large image without full-size copies."""
    return [slice(start, min(start + rows_per_band, height)) for start in range(0, height, rows_per_band)]
