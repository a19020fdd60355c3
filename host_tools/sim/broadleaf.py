"""Top-down broadleaf crowns: citrus (one dense round crown) and olive (grey-green, a double-ring look).

Their HOG signatures are what the paper's generalization models learn: a single circle for citrus and a double
circle for olive (an open, vase-pruned canopy whose outer and inner foliage rings are split by a shadowed gap).
"""
import math

import numpy as np

from host_tools.sim.sprite import Sprite, canvas_for, radial_shading

CITRUS_LEAVES = ((30, 95, 45), (40, 120, 60), (25, 80, 38), (55, 140, 80))
CITRUS_FRUIT = (20, 120, 235)
OLIVE_LEAVES = ((100, 135, 115), (118, 152, 132), (85, 110, 95), (138, 165, 150))
OLIVE_GAP = (70, 92, 92)


def render_citrus(rng: np.random.Generator, centre_col: float, centre_row: float, diameter_px: float,
                  light: float = 1.0, sun_dir: tuple[float, float] = (0.7, -0.7)) -> Sprite:
    canvas, centre, origin = canvas_for(centre_col, centre_row, diameter_px)
    radius = diameter_px / 2.0
    tint = light * rng.uniform(0.9, 1.1, size=3) ** 0.3
    canvas.polygon(_lumpy_outline(rng, centre, radius * 0.97, 0.06), np.array(CITRUS_LEAVES[0]) * tint)
    _leaf_clumps(canvas, rng, centre, 0.0, radius * 0.9, diameter_px, CITRUS_LEAVES, tint, density=1.0)
    if rng.random() < 0.5:  # a few fruits
        for _ in range(int(rng.integers(3, 12))):
            r, a = radius * 0.8 * math.sqrt(rng.random()), rng.uniform(0, 2 * math.pi)
            canvas.circle(centre + r * np.array([math.cos(a), math.sin(a)]), 0.022 * diameter_px,
                          np.array(CITRUS_FRUIT) * light)
    shading = radial_shading(canvas.size, centre, radius, sun_dir, 0.25)
    return canvas.to_sprite(origin, blur_sigma=0.003 * diameter_px, shading=shading)


def render_olive(rng: np.random.Generator, centre_col: float, centre_row: float, diameter_px: float,
                 light: float = 1.0, sun_dir: tuple[float, float] = (0.7, -0.7)) -> Sprite:
    canvas, centre, origin = canvas_for(centre_col, centre_row, diameter_px)
    radius = diameter_px / 2.0
    tint = light * rng.uniform(0.9, 1.1, size=3) ** 0.3
    # dark interior (shadowed branches) seen through the gap between the rings
    canvas.circle(centre, radius * 0.66, np.array(OLIVE_GAP) * tint)
    _ring(canvas, rng, centre, radius * 0.68, radius * 0.98, diameter_px, tint)
    _ring(canvas, rng, centre, radius * 0.18, radius * 0.46, diameter_px, tint)
    shading = radial_shading(canvas.size, centre, radius, sun_dir, 0.2)
    return canvas.to_sprite(origin, blur_sigma=0.002 * diameter_px, shading=shading)


def _ring(canvas, rng, centre, inner, outer, diameter_px, tint):
    mid, half = (inner + outer) / 2.0, (outer - inner) / 2.0
    angles = np.linspace(0, 2 * np.pi, 48, endpoint=False)
    wobble = 1.0 + 0.08 * _smooth_noise(rng, 48)
    outer_pts = centre + (mid + half * wobble)[:, None] * np.stack([np.cos(angles), np.sin(angles)], 1)
    inner_pts = centre + (mid - half * wobble[::-1])[:, None] * np.stack([np.cos(angles), np.sin(angles)], 1)
    band = np.concatenate([outer_pts, outer_pts[:1], inner_pts[:1], inner_pts[::-1]])
    canvas.polygon(band, np.array(OLIVE_LEAVES[2]) * tint)
    _leaf_clumps(canvas, rng, centre, inner, outer, diameter_px, OLIVE_LEAVES, tint, density=0.8)


def _leaf_clumps(canvas, rng, centre, r_min, r_max, diameter_px, colours, tint, density):
    """Many small leaf clusters (ellipses) scattered over an annulus: the crown's speckled texture."""
    area = math.pi * (r_max ** 2 - r_min ** 2)
    size = 0.028 * diameter_px
    n = int(density * area / (size * size))
    r = np.sqrt(rng.uniform(r_min ** 2, r_max ** 2, n))
    a = rng.uniform(0, 2 * math.pi, n)
    pts = centre + np.stack([r * np.cos(a), r * np.sin(a)], 1)
    shade = rng.integers(0, len(colours), n)
    axes = rng.uniform(0.5, 1.0, (n, 2)) * size
    tilt = rng.uniform(0, 180, n)
    for i in range(n):
        canvas.ellipse(pts[i], axes[i], tilt[i], np.array(colours[shade[i]]) * tint)


def _lumpy_outline(rng, centre, radius, amount, points=64):
    angles = np.linspace(0, 2 * np.pi, points, endpoint=False)
    r = radius * (1.0 - amount + amount * _smooth_noise(rng, points))
    return centre + r[:, None] * np.stack([np.cos(angles), np.sin(angles)], 1)


def _smooth_noise(rng, n, harmonics=5):
    """Periodic smooth noise in [-1, 1] around a circle."""
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    out = np.zeros(n)
    for k in range(2, 2 + harmonics):
        out += rng.normal(0, 1.0 / k) * np.cos(k * t + rng.uniform(0, 2 * np.pi))
    peak = np.abs(out).max()
    return out / peak if peak > 0 else out
