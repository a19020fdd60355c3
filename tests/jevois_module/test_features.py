"""The detector's feature definitions (jevois_module/ForaNavTrees/foranav_features.py)."""
import cv2
import numpy as np
import pytest

import host_tools.detection  # noqa: F401  (camera module folder on sys.path)
import foranav_features as features

DESCRIPTOR_TOLERANCE = 1e-5


def half_plane(angle_deg, size=24):
    """A dark/bright half-plane whose edge normal points at angle_deg (image x right, y down)."""
    yy, xx = np.mgrid[0:size, 0:size] - (size - 1) / 2.0
    normal = np.cos(np.radians(angle_deg)) * xx + np.sin(np.radians(angle_deg)) * yy
    return np.where(normal > 0, 200, 50).astype(np.uint8)


def test_that_the_descriptor_length_follows_the_hog_formula():
    # 24 px / 6 px cells = 4 cells; blocks of 3 at stride 1 -> 2 x 2 blocks of 3 x 3 cells x 9 bins
    assert features.hog_descriptor_length() == 2 * 2 * 3 * 3 * 9 == 324
    assert features.hog_descriptor_length(window=30) == 3 * 3 * 81
    assert features.top_layer_hog(np.zeros((24, 24), np.uint8)).shape == (324,)


def test_that_every_orientation_level_votes_a_whole_pixel_into_at_most_two_neighbouring_bins():
    assert np.allclose(features.SOFT_BIN_TABLE.sum(axis=1), 1.0)
    assert (np.count_nonzero(features.SOFT_BIN_TABLE, axis=1) <= 2).all()
    assert np.abs(features.SOFT_BIN_TABLE_U8.sum(axis=1).astype(int) - 255).max() <= 1


@pytest.mark.parametrize("angle", [0, 90, 180, 270])
def test_that_a_rotated_half_plane_fills_one_orientation_bin(angle):
    # Fixture: a straight edge at 0/90/180/270 deg; unsigned orientation folds 180 onto 0.
    histogram = features.global_orientation_histogram(half_plane(angle))
    # Assert: the edge's bins (0 deg sits between bins 8 and 0; 90 deg at the border of bins 4 and 5) hold it all.
    expected = {0: (8, 0), 180: (8, 0), 90: (4, 5), 270: (4, 5)}[angle]
    assert histogram[list(expected)].sum() == pytest.approx(histogram.sum(), rel=1e-6)
    assert histogram.sum() > 0


def test_that_a_flat_window_has_zero_variance_and_a_zero_descriptor():
    flat = np.full((60, 60), 120, np.uint8)
    assert features.hog_global_variance(flat) == 0.0
    assert np.abs(features.top_layer_hog(flat[:24, :24])).max() == 0.0


def test_that_fine_texture_has_higher_bottom_layer_variance_than_smooth_texture():
    rng = np.random.RandomState(1)
    fine = np.zeros((96, 96), np.uint8)
    for _ in range(60):  # thin needle-like strokes of one dominant direction family
        x, y = rng.randint(0, 96, 2)
        cv2.line(fine, (int(x), int(y)), (int(x) + 12, int(y) + 3), 220, 1)
    smooth = cv2.GaussianBlur(fine, (0, 0), 4)
    assert features.hog_global_variance(fine) > 5 * features.hog_global_variance(smooth)


def test_that_blocks_are_l2_normalised():
    rng = np.random.RandomState(2)
    descriptor = features.top_layer_hog(rng.randint(0, 255, (24, 24)).astype(np.uint8))
    norms = np.linalg.norm(descriptor.reshape(4, 81), axis=1)
    assert np.allclose(norms, 1.0, atol=1e-3)  # textured blocks: eps is negligible


def test_that_the_bottom_layer_texture_cue_ignores_light_and_gain_but_not_blur():
    rng = np.random.RandomState(6)
    fine = np.full((96, 96), 60, np.uint8)
    for _ in range(80):  # thin needle-like strokes
        x, y = rng.randint(0, 96, 2)
        cv2.line(fine, (int(x), int(y)), (int(x) + 12, int(y) + 3), 200, 1)
    dim = cv2.convertScaleAbs(fine, alpha=0.5)  # half the light: Var_hog drops 4 x
    assert features.hog_global_variance(dim) < 0.3 * features.hog_global_variance(fine)
    assert features.hog_texture(dim) == pytest.approx(features.hog_texture(fine), rel=0.2)  # the contrast floor
    blurred = cv2.GaussianBlur(fine, (0, 0), 2.0)  # coarse texture, same light
    assert features.hog_texture(blurred) < 0.5 * features.hog_texture(fine)
    assert features.hog_texture(np.full((60, 60), 120, np.uint8)) == 0.0


def test_that_a_window_with_context_equals_the_crop_of_the_downscaled_frame_for_aligned_windows():
    rng = np.random.RandomState(4)
    value = rng.randint(0, 255, (288, 352)).astype(np.uint8)
    window = 96  # 4 x 24: downscaling is an exact 4 x 4 block mean
    small_frame = features.downscale_value(value, window)
    for x0, y0 in [(40, 60), (0, 0), (352 - 96, 288 - 96)]:
        small = features.window_with_context(value, x0, y0, window)
        inner = small[1:-1, 1:-1]
        assert np.array_equal(inner, small_frame[y0 // 4:y0 // 4 + 24, x0 // 4:x0 // 4 + 24])
        descriptor = features.top_layer_hog(small)
        assert descriptor.shape == (324,)


def test_that_bad_window_shapes_are_refused():
    with pytest.raises(ValueError):
        features.top_layer_hog(np.zeros((20, 20), np.uint8))
    with pytest.raises(ValueError):
        features.hog_global_variance(np.zeros((0, 5), np.uint8))
