"""The detector's grouping of score-map peaks into trees (jevois_module/ForaNavTrees/foranav_grouping.py)."""
import numpy as np

import host_tools.detection  # noqa: F401  (puts the camera module folder on sys.path)
import foranav_grouping as grouping


class _GridPlan(object):
    """A score map's geometry for the peak tests: lattice positions 8 px apart, 96 px windows."""
    window = 96

    def window_origin(self, row, col):
        return col * 8.0, row * 8.0


def _score_map_with_peaks(peaks, shape=(12, 16), floor=-3.0):
    scores = np.full(shape, floor, np.float32)
    for (row, col), score in peaks.items():
        scores[row, col] = score
    return scores


def test_that_a_weak_peak_on_the_score_map_border_is_dropped_but_a_strong_one_and_inner_ones_are_kept():
    # Fixture: peaks at -0.5 on the border (a crown cut by the frame edge) and inside, 1.0 on the border.
    scores = _score_map_with_peaks({(0, 5): -0.5, (6, 8): -0.5, (11, 2): 1.0, (4, 15): -0.2})
    kept = grouping.local_maxima(_GridPlan(), scores, -1.5, edge_threshold=0.0)
    assert sorted(round(c[0], 2) for c in kept) == [-0.5, 1.0]
    assert [(c[1], c[2]) for c in kept if c[0] < 0] == [(8 * 8 + 48, 6 * 8 + 48)]  # the inner peak
    # without the edge rule every peak above the SVM threshold is a candidate
    assert len(grouping.local_maxima(_GridPlan(), scores, -1.5, edge_threshold=None)) == 4


def test_that_a_window_centred_inside_an_accepted_crown_is_the_same_tree_but_a_neighbour_is_not():
    accepted = [grouping.Detection(150.0, 100.0, 129.0, 129.0, 1.2)]  # from a 168 px window (x 1.3)
    side_window = (-0.7, 150.0, 145.0, 96.0)  # 45 px off the crown centre
    neighbour = (-0.7, 150.0 + 129.0, 100.0, 168.0)  # one crown diameter away
    assert grouping.iou(side_window, (1.2, 150.0, 100.0, 168.0)) < grouping.DEFAULT_NMS_OVERLAP
    assert grouping.inside_a_crown(side_window, accepted, 1.3)
    assert not grouping.inside_a_crown(neighbour, accepted, 1.3)


def test_that_a_large_window_straddling_an_accepted_crown_and_the_gap_beside_it_is_that_crown():
    # sweep flight 468 at 1.46 m: tree 2 found by a 120 px window, a 168 px window over its lower half and
    # the gap towards tree 1 (IoU 0.28, under the NMS overlap) reported a tree between the two trees
    accepted = [grouping.Detection(180.0, 87.0, 92.3, 92.3, 0.16)]  # from a 120 px window (x 1.3)
    straddling = (-1.42, 177.0, 153.0, 168.0)
    assert grouping.iou(straddling, (0.16, 180.0, 87.0, 120.0)) < grouping.DEFAULT_NMS_OVERLAP
    assert grouping.inside_a_crown(straddling, accepted, 1.3)
    # touching neighbours one size step apart (1.3 and 1.73 crowns, centres one crown apart) stay two trees
    crown = 92.3
    neighbour = (-1.42, 180.0, 87.0 + crown, 168.0)
    assert not grouping.inside_a_crown(neighbour, accepted, 1.3)


def test_that_the_crown_sized_window_holding_an_off_centre_best_window_anchors_the_group():
    # straight above a 0.45 m crown at 1.1 m (130 px): a 96 px window on its fronds 30 px off centre scored
    # best; the 168 px window holding it, within SCALE_TIE, is centred on the crown
    off_centre = (-0.70, 197.0, 121.0, 96.0)
    crown_sized = (-0.72, 170.0, 151.0, 168.0)
    elsewhere = (-0.71, 120.0, 200.0, 168.0)  # scores as well but does not hold the best window
    group = [off_centre, elsewhere, crown_sized]
    assert grouping.anchored(group)[0] is crown_sized
    assert sorted(map(id, grouping.anchored(group))) == sorted(map(id, group))
    # a larger window scoring much worse does not take over
    weak = (-0.70 - 2 * grouping.SCALE_TIE, 170.0, 151.0, 168.0)
    assert grouping.anchored([off_centre, weak])[0] is off_centre
