"""Single specimens and the README gallery: every kind renders, and each looks different from bare ground."""
import numpy as np
import pytest

from host_tools.sim.gallery import COLUMNS, LABEL_HEIGHT, TILE_SCALE, gallery
from host_tools.sim.specimens import KINDS, render_specimen

MIN_COLOUR_DIFFERENCE = 20.0  # grey levels (sum over B, G, R) between the crop's centre and its corners


def centre_minus_corners(crop):
    """Distance between the mean colours of the central 40 % and of the four corner 15 % squares."""
    side = crop.shape[0]
    c0, c1, k = int(side * 0.3), int(side * 0.7), int(side * 0.15)
    centre = crop[c0:c1, c0:c1].reshape(-1, 3).mean(axis=0)
    corners = np.concatenate([crop[:k, :k], crop[:k, -k:], crop[-k:, :k], crop[-k:, -k:]]).reshape(-1, 3)
    return np.abs(centre - corners.mean(axis=0)).sum()


@pytest.mark.parametrize("kind", [k for k in KINDS if k != "ground"])
def test_that_a_specimen_stands_out_from_its_ground(kind):
    crop = render_specimen(kind, seed=9, size_m=0.4)
    side = int(round(0.4 * 1.3 / (1.25 * 0.0031)))
    assert crop.shape == (side, side, 3)
    assert centre_minus_corners(crop) > MIN_COLOUR_DIFFERENCE


def test_that_bare_ground_has_no_such_centre():
    assert centre_minus_corners(render_specimen("ground", seed=9, size_m=0.4)) < MIN_COLOUR_DIFFERENCE


def test_that_the_gallery_has_one_labelled_tile_per_kind():
    image = gallery()
    rows = -(-len(KINDS) // COLUMNS)
    tile = image.shape[1] // COLUMNS
    assert image.shape[0] == rows * (tile + LABEL_HEIGHT)
    assert tile % TILE_SCALE == 0
