"""Top-down palms: a star of pinnate fronds. Oil palm (the target) and its look-alikes coconut and date palm.

The three share the star shape (what the detector's top-layer HOG sees) and differ where the paper's cues
look: oil palm leaflets are fine, needle-like and high-contrast against a dark under-canopy (high bottom-layer
HOG variance); coconut leaflets are broad, drooping and soft; date palm leaflets are stiff, grey-blue and stick
out at scattered angles on a grey under-canopy (low contrast, no dominant orientation).
All lengths are fractions of the crown diameter so the palms draw at any pixel scale.
"""
import math
from dataclasses import dataclass

import numpy as np

from host_tools.sim.sprite import Sprite, canvas_for, radial_shading


@dataclass(frozen=True)
class PalmStyle:
    fronds: tuple  # (min, max) number of fronds
    frond_length: tuple  # (min, max) fraction of the crown radius (the longest frond reaches the crown edge)
    curl: float  # lateral bend of the frond tip, fraction of its length (std)
    leaflet_spacing: float  # along the rachis, fraction of the crown diameter
    leaflet_length: float  # longest leaflet, fraction of the frond length
    leaflet_angle_deg: tuple  # (min, max) angle between leaflet and rachis (towards the tip), drawn per frond
    leaflet_jitter_deg: float  # per-leaflet deviation from the frond's angle (std): regular vs ragged
    leaflet_width: float  # fraction of the crown diameter (line thickness)
    leaflet_colours: tuple  # BGR shades, drawn at random per leaflet
    rachis_colour: tuple
    core_colour: tuple  # the under-canopy seen between leaflets
    core_radius: float  # fraction of the crown radius
    blur: float  # softening, fraction of the crown diameter (Gaussian sigma)
    shading: float  # sun-side brightening


OIL_PALM = PalmStyle(
    fronds=(9, 13), frond_length=(0.88, 1.0), curl=0.05, leaflet_spacing=0.042, leaflet_length=0.27,
    leaflet_angle_deg=(45, 60), leaflet_jitter_deg=3.0, leaflet_width=0.011,
    leaflet_colours=((40, 175, 120), (55, 200, 150), (65, 220, 170), (35, 150, 95)),
    rachis_colour=(50, 150, 150), core_colour=(12, 38, 28), core_radius=0.6, blur=0.0, shading=0.18)

COCONUT = PalmStyle(
    fronds=(18, 24), frond_length=(0.82, 1.0), curl=0.3, leaflet_spacing=0.036, leaflet_length=0.26,
    leaflet_angle_deg=(12, 30), leaflet_jitter_deg=10.0, leaflet_width=0.022,
    leaflet_colours=((70, 185, 170), (80, 195, 180), (62, 170, 155)),
    rachis_colour=(90, 200, 200), core_colour=(55, 140, 125), core_radius=0.3, blur=0.009, shading=0.12)

DATE_PALM = PalmStyle(
    fronds=(24, 32), frond_length=(0.75, 1.0), curl=0.03, leaflet_spacing=0.032, leaflet_length=0.2,
    leaflet_angle_deg=(20, 65), leaflet_jitter_deg=20.0, leaflet_width=0.011,
    leaflet_colours=((118, 150, 120), (128, 162, 130), (110, 140, 112)),
    rachis_colour=(140, 170, 150), core_colour=(95, 118, 100), core_radius=0.4, blur=0.003, shading=0.1)

STYLES = {"oil_palm": OIL_PALM, "coconut": COCONUT, "date_palm": DATE_PALM}


def render_palm(style: PalmStyle, rng: np.random.Generator, centre_col: float, centre_row: float,
                diameter_px: float, light: float = 1.0, sun_dir: tuple[float, float] = (0.7, -0.7)) -> Sprite:
    """Draw one palm crown of the given diameter centred at a continuous image position -> Sprite."""
    canvas, centre, origin = canvas_for(centre_col, centre_row, diameter_px)
    radius = diameter_px / 2.0
    tint = light * rng.uniform(0.9, 1.1, size=3) ** 0.3  # small colour cast per tree
    canvas.circle(centre, radius * style.core_radius, np.array(style.core_colour) * tint)
    n = int(rng.integers(style.fronds[0], style.fronds[1] + 1))
    base = rng.uniform(0.0, 2.0 * math.pi)
    # two whorls: older long fronds drawn first, younger shorter ones on top in the gaps
    order = [k for k in range(n) if k % 2 == 0] + [k for k in range(n) if k % 2 == 1]
    for k in order:
        angle = base + 2.0 * math.pi * k / n + rng.normal(0.0, 0.25 * 2.0 * math.pi / n)
        reach = rng.uniform(*style.frond_length) * (1.0 if k % 2 == 0 else rng.uniform(0.78, 0.92))
        _draw_frond(canvas, rng, style, centre, angle, reach * radius * 0.97, diameter_px, tint)
    shading = radial_shading(canvas.size, centre, radius, sun_dir, style.shading)
    return canvas.to_sprite(origin, blur_sigma=style.blur * diameter_px, shading=shading)


def _draw_frond(canvas, rng, style, centre, angle, length, diameter_px, tint):
    """One pinnate frond: a (slightly bent) rachis with leaflets on both sides."""
    direction = np.array([math.cos(angle), math.sin(angle)])
    normal = np.array([-direction[1], direction[0]])
    bend = rng.normal(0.0, style.curl) * length
    s = np.linspace(0.0, 1.0, 12)
    rachis = centre + np.outer(s * length, direction) + np.outer(bend * s * s, normal)
    width = max(1, int(round(style.leaflet_width * diameter_px)))
    canvas.polylines([rachis], np.array(style.rachis_colour) * tint, thickness=max(1, width))

    spacing = max(style.leaflet_spacing * diameter_px, 1.2) / length
    s = np.arange(0.1, 0.98, spacing) + rng.uniform(0.0, spacing)
    s = s[s < 0.98]
    base = centre + np.outer(s * length, direction) + np.outer(bend * s * s, normal)
    tangent = direction[None, :] + np.outer(2.0 * bend * s / length, normal)
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    side_normal = np.stack([-tangent[:, 1], tangent[:, 0]], axis=1)
    profile = np.sin(np.pi * np.clip((s - 0.05) / 0.97, 0.0, 1.0)) ** 0.7  # short at the base and the tip
    leaflet_len = style.leaflet_length * length * profile
    colours = np.array(style.leaflet_colours, dtype=float)
    frond_angle = rng.uniform(*style.leaflet_angle_deg)
    for side in (1.0, -1.0):
        alpha = np.radians(frond_angle + rng.normal(0.0, style.leaflet_jitter_deg, size=len(s)))
        ends = base + leaflet_len[:, None] * (np.cos(alpha)[:, None] * tangent
                                              + side * np.sin(alpha)[:, None] * side_normal)
        shade = rng.integers(0, len(colours), size=len(s))
        for i, colour in enumerate(colours):
            pick = shade == i
            canvas.segments(base[pick], ends[pick], colour * tint, thickness=width)
