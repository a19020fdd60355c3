"""The paper's non-vegetation look-alikes, top-down: roofs and road intersections.

Both make star-like gradients (a hip roof's ridges and hips form an X with tile lines parallel to the eaves; a
crossing is arms radiating from a centre) but with non-vegetation hue and saturation, which is what the
detector's hue/saturation comparison rejects. ``yaw_img`` is the object's axis angle in the image (radians).
"""
import math

import numpy as np

from host_tools.sim.sprite import Sprite, canvas_for

ROOF_COLOURS = ((55, 85, 185), (45, 60, 140), (140, 140, 135), (160, 110, 60), (110, 120, 150))
ASPHALT = ((95, 95, 95), (80, 82, 85), (120, 150, 175))  # dark asphalt, older asphalt, dirt road
MARKING = (225, 230, 230)


def roof_footprint(size_m: float, aspect: float) -> tuple[float, float]:
    """Half extents (along, across) of a roof of the given size (the long side) and aspect (short/long)."""
    return size_m / 2.0, size_m * aspect / 2.0


def render_roof(rng: np.random.Generator, centre_col: float, centre_row: float, size_px: float, aspect: float,
                yaw_img: float, light: float = 1.0, sun_dir: tuple[float, float] = (0.7, -0.7)) -> Sprite:
    """A hip roof seen from above: four shaded facets with tile lines, ridge and hips."""
    canvas, centre, origin = canvas_for(centre_col, centre_row, size_px * 1.05)
    half_l, half_w = size_px / 2.0, size_px * aspect / 2.0
    axis = np.array([math.cos(yaw_img), math.sin(yaw_img)])
    across = np.array([-axis[1], axis[0]])

    def to_img(along, cross):  # roof coordinates (along the ridge, across it) -> canvas pixels
        return centre + along * axis + cross * across

    ridge = max(half_l - half_w, 0.0)
    corners = [to_img(-half_l, -half_w), to_img(half_l, -half_w), to_img(half_l, half_w), to_img(-half_l, half_w)]
    r0, r1 = to_img(-ridge, 0.0), to_img(ridge, 0.0)
    facets = [((corners[0], corners[1], r1, r0), -across), ((corners[2], corners[3], r0, r1), across),
              ((corners[3], corners[0], r0), -axis), ((corners[1], corners[2], r1), axis)]
    base = np.array(ROOF_COLOURS[int(rng.integers(len(ROOF_COLOURS)))]) * light
    spacing = max(size_px * 0.035, 1.5)
    for points, outward in facets:
        brightness = 0.85 + 0.25 * float(np.dot(outward, sun_dir))
        canvas.polygon(np.array(points), base * brightness)
        _tile_lines(canvas, np.array(points), outward, spacing, base * brightness * 0.7)
    line = base * 1.25
    canvas.polylines([np.array([r0, r1])], line, thickness=max(1, int(size_px * 0.012)))
    for c, r in ((corners[0], r0), (corners[3], r0), (corners[1], r1), (corners[2], r1)):
        canvas.polylines([np.array([c, r])], line, thickness=max(1, int(size_px * 0.01)))
    canvas.polylines([np.array(corners)], base * 0.5, thickness=max(1, int(size_px * 0.01)), closed=True)
    return canvas.to_sprite(origin, blur_sigma=0.002 * size_px)


def _tile_lines(canvas, polygon, outward, spacing, colour):
    """Lines parallel to the facet's eave (perpendicular to its outward direction), clipped to the facet."""
    depth = polygon @ outward
    lo, hi = depth.min(), depth.max()
    eave_dir = np.array([-outward[1], outward[0]])
    starts, ends = [], []
    for d in np.arange(lo + spacing, hi, spacing):
        seg = _clip_line_to_polygon(polygon, outward, eave_dir, d)
        if seg is not None:
            starts.append(seg[0])
            ends.append(seg[1])
    if starts:
        canvas.segments(np.array(starts), np.array(ends), colour, thickness=1)


def _clip_line_to_polygon(polygon, normal, direction, offset):
    """Segment of the line {p : p . normal = offset} inside a convex polygon, or None."""
    hits = []
    n = len(polygon)
    for i in range(n):
        a, b = polygon[i], polygon[(i + 1) % n]
        da, db = a @ normal - offset, b @ normal - offset
        if da == db or da * db > 0:
            continue
        t = da / (da - db)
        hits.append(a + t * (b - a))
    if len(hits) < 2:
        return None
    hits = sorted(hits, key=lambda p: p @ direction)
    return hits[0], hits[-1]


def render_road_cross(rng: np.random.Generator, centre_col: float, centre_row: float, size_px: float, yaw_img: float,
                      light: float = 1.0) -> Sprite:
    """Two (sometimes three) roads crossing, arms fading into the ground at the object's extent."""
    canvas, centre, origin = canvas_for(centre_col, centre_row, size_px * 1.45)
    half = size_px / 2.0
    width = size_px * rng.uniform(0.22, 0.32)
    surface = np.array(ASPHALT[int(rng.integers(len(ASPHALT)))]) * light
    arms = [0.0, math.pi / 2]
    if rng.random() < 0.3:
        arms.append(math.pi / 4 + rng.normal(0, 0.1))
    for k, arm in enumerate(arms):
        d = np.array([math.cos(yaw_img + arm), math.sin(yaw_img + arm)])
        n = np.array([-d[1], d[0]])
        quad = np.array([centre - half * d - width / 2 * n, centre + half * d - width / 2 * n,
                         centre + half * d + width / 2 * n, centre - half * d + width / 2 * n])
        canvas.polygon(quad, surface * (1.0 + 0.04 * k))
    for arm in arms:  # edge lines and dashed centre lines
        d = np.array([math.cos(yaw_img + arm), math.sin(yaw_img + arm)])
        n = np.array([-d[1], d[0]])
        for side in (-1, 1):
            edge = [centre - half * d + side * 0.42 * width * n, centre + half * d + side * 0.42 * width * n]
            canvas.polylines([np.array(edge)], np.array(MARKING) * light, thickness=max(1, int(width * 0.04)))
        dash = size_px * 0.05
        for t in np.arange(width * 0.7, half, 2 * dash):
            for sign in (-1, 1):
                seg = [centre + sign * t * d, centre + sign * min(t + dash, half) * d]
                canvas.polylines([np.array(seg)], np.array(MARKING) * light, thickness=max(1, int(width * 0.05)))
    sprite = canvas.to_sprite(origin, blur_sigma=0.002 * size_px)
    # speckle the surface (gravel, wear) so it is not a flat colour
    noise = rng.normal(1.0, 0.06, sprite.alpha.shape).astype(np.float32)
    sprite.premultiplied *= noise[..., None]
    return sprite
