"""The row fit through crown centres: heading search, gaps, bends, triangular planting, a given heading."""
import math

import numpy as np
import pytest

from host_tools.photo_rows import best_heading, fit_rows

CROWN = 0.35
HEADING_TOLERANCE_DEG = 1.0
SPACING_TOLERANCE = 0.05  # relative


def rows_of_palms(heading_deg, rows=5, palms=8, palm_spacing=0.45, row_spacing=0.6, jitter=0.02, seed=0,
                  triangular=False, bend_deg_per_palm=0.0, missing=()):
    """Centres (N, 2) of straight or bent rows at a heading, with jitter and missing palms."""
    rng = np.random.default_rng(seed)
    h = math.radians(heading_deg)
    along, across = np.array([math.cos(h), math.sin(h)]), np.array([-math.sin(h), math.cos(h)])
    points, index = [], 0
    for r in range(rows):
        p = across * r * row_spacing + along * (palm_spacing / 2 if triangular and r % 2 else 0.0)
        direction = along.copy()
        for k in range(palms):
            index += 1
            if index not in missing:
                points.append(p + rng.normal(0, jitter, 2))
            turn = math.radians(bend_deg_per_palm)
            direction = np.array([direction[0] * math.cos(turn) - direction[1] * math.sin(turn),
                                  direction[0] * math.sin(turn) + direction[1] * math.cos(turn)])
            p = p + direction * palm_spacing
    return np.array(points)


def heading_error(a, b):
    d = abs(a - b) % 180.0
    return min(d, 180.0 - d)


@pytest.mark.parametrize("heading", [0.0, 33.0, 90.0, 141.5])
def test_that_the_row_direction_is_found_at_any_heading(heading):
    # Fixture
    points = rows_of_palms(heading, seed=int(heading))
    # Test
    fit = fit_rows(points, CROWN)
    # Assert
    assert heading_error(fit.heading_deg, heading) <= HEADING_TOLERANCE_DEG
    assert len(fit.rows) == 5
    assert sum(len(r.members) for r in fit.rows) == len(points)
    assert fit.row_spacing == pytest.approx(0.6, rel=SPACING_TOLERANCE)


def test_that_missing_palms_do_not_split_or_lose_a_row():
    points = rows_of_palms(20.0, missing=(3, 4, 12, 30, 31), seed=4)
    fit = fit_rows(points, CROWN)
    assert len(fit.rows) == 5
    assert sum(len(r.members) for r in fit.rows) == len(points)


def test_that_a_triangular_planting_gives_rows_along_a_lattice_direction():
    # rows 0.39 m apart, palms 0.45 m: the three lattice directions are 60 degrees apart
    points = rows_of_palms(10.0, rows=7, palms=9, row_spacing=0.45 * math.sqrt(3) / 2, triangular=True, seed=2)
    fit = fit_rows(points, CROWN)
    assert min(heading_error(fit.heading_deg, 10.0 + k * 60.0) for k in range(3)) <= HEADING_TOLERANCE_DEG
    assert fit.row_spacing == pytest.approx(0.45 * math.sqrt(3) / 2, rel=0.1)
    for row in fit.rows:  # every row is a straight line of palms, not a zig-zag between two rows
        assert len(row.line) == 2


def test_that_a_bent_row_keeps_its_palms_and_gets_a_polyline_through_the_bend():
    points = rows_of_palms(0.0, rows=3, palms=10, bend_deg_per_palm=3.0, row_spacing=0.8, seed=3)
    fit = fit_rows(points, CROWN)
    assert len(fit.rows) == 3
    assert sum(len(r.members) for r in fit.rows) == len(points)
    assert all(len(r.line) > 2 for r in fit.rows)
    for row in fit.rows:  # every palm lies near its row's polyline
        line = np.array(row.line)
        for i in row.members:
            d = min(_segment_distance(points[i], a, b) for a, b in zip(line[:-1], line[1:]))
            assert d <= 0.3 * CROWN + 0.03


def test_that_a_given_heading_is_used_as_is():
    points = rows_of_palms(0.0, seed=5)
    fit = fit_rows(points, CROWN, heading_deg=90.0)
    assert fit.heading_deg == 90.0
    assert best_heading(points, CROWN) == pytest.approx(0.0, abs=HEADING_TOLERANCE_DEG)


def test_that_scattered_points_make_no_row():
    rng = np.random.default_rng(9)
    points = rng.uniform(0, 6, (4, 2))
    assert fit_rows(points, CROWN).rows == ()


def _segment_distance(p, a, b):
    ab, ap = b - a, p - a
    t = max(0.0, min(1.0, float(ap @ ab) / float(ab @ ab)))
    return float(np.hypot(*(ap - t * ab)))
