# ForaNav tree detector: the colour test's definitions, shared by training, the camera and the host tools.
#
# Paper section III-A's colour check: 256-bin hue and saturation histograms of the window's central region
# (the crown); the mean of their Pearson correlations (paper eq. 6) with the imagery's template must exceed a
# threshold (rejects roofs, road crossings and other palms' colours). HSV is OpenCV's COLOR_BGR2HSV_FULL
# (foranav_features.bgr_to_hsv): hue 0..255 covers the full circle, so 256 hue bins are all used. Both
# histograms are smoothed before they are compared. A model holds one colour model per imagery
# (foranav_model: colour_kind, colour_vectors, colour_bias), and each imagery's mean whole-frame colour, by
# which the detector picks the imagery of a frame. Camera and host alike (Python 3.7, numpy 1.16, OpenCV 4.10).
import cv2
import numpy as np

HS_BINS = 256  # hue and saturation histogram bins
HS_SMOOTHING_BINS = 4.0  # Gaussian sigma applied to both histograms before correlating them (0 = none)


def hs_histograms(hsv_window_uint8):
    """(hue_hist, sat_hist): 256-bin float32 pixel counts of an HSV_FULL window."""
    hsv = np.ascontiguousarray(hsv_window_uint8)
    if hsv.ndim != 3 or hsv.shape[2] != 3 or hsv.size == 0:
        raise ValueError("HSV window must be a non-empty H x W x 3 array")
    hue = cv2.calcHist([hsv], [0], None, [HS_BINS], [0, 256]).ravel()
    sat = cv2.calcHist([hsv], [1], None, [HS_BINS], [0, 256]).ravel()
    return hue, sat


def pearson(a, b):
    """Pearson correlation of two histograms (paper eq. 6); 0 when either is constant."""
    a = np.asarray(a, np.float64).ravel()
    b = np.asarray(b, np.float64).ravel()
    da = a - a.mean()
    db = b - b.mean()
    denominator = np.sqrt(da.dot(da) * db.dot(db))
    return float(da.dot(db) / denominator) if denominator > 0 else 0.0


def smooth_histogram(histogram, sigma=HS_SMOOTHING_BINS):
    """Gaussian-smoothed copy (float32) of a 1-D histogram (its ends reflected).

    Raw 256-bin histograms of a few thousand pixels are spiky, and a slight change of light or white
    balance moves every spike: their Pearson correlation then measures the noise. Smoothing both sides
    over a few bins makes the comparison about the colour distribution's shape.
    """
    histogram = np.asarray(histogram, np.float32).reshape(1, -1)
    if sigma <= 0:
        return histogram.ravel()
    return cv2.GaussianBlur(histogram, (0, 0), sigmaX=sigma, borderType=cv2.BORDER_REFLECT).ravel()


COLOUR_REGION_FRACTION = 0.6  # side of the colour test's central square / window side


def colour_region(window):
    """The central square of a window (a view) whose hue and saturation the colour test compares.

    A window is 1.3 x the crown, so a whole-window histogram is about 40 % ground and shadow, and the
    ground's colour, which a coconut, a roof or a palm share, dominated it. The central 0.6 x W (about 0.8 of
    the crown) holds the crown alone. Measured on the rendered hold-out (seed 911) with the template made the
    same way from training crops, at the oil palms' 2 % quantile: coconuts passing 100 % -> 0 %, road
    crossings 50 % -> 0 %, roofs 30 % -> 0 %, background 70 % -> 7 %; and the two flight-map palms whose
    whole-window similarity fell in the palms' lowest 2 % rank at 8 % and 93 % instead.
    """
    side = window.shape[0]
    inner = max(1, int(round(side * COLOUR_REGION_FRACTION)))
    top = (side - inner) // 2
    width = window.shape[1]
    inner_w = max(1, int(round(width * COLOUR_REGION_FRACTION)))
    left = (width - inner_w) // 2
    return window[top:top + inner, left:left + inner_w]


def hs_similarity(hsv_window, template_h, template_s):
    """Mean of the Pearson correlations (paper eq. 6) of the hue and saturation histograms of the window's
    colour_region with the template's, both smoothed by HS_SMOOTHING_BINS (-1..1; 1 = same colour distribution)."""
    return hs_similarity_to_smoothed(hsv_window, smooth_histogram(template_h), smooth_histogram(template_s))


def hs_similarity_to_smoothed(hsv_window, smooth_template_h, smooth_template_s):
    """hs_similarity with the template histograms already smoothed (the detector smooths them once)."""
    hue, sat = hs_histograms(colour_region(hsv_window))
    return 0.5 * (pearson(smooth_histogram(hue), smooth_template_h) + pearson(smooth_histogram(sat),
                                                                              smooth_template_s))


# Colour models of one imagery (foranav_model: colour_kind, colour_vectors, colour_bias)

COLOUR_KINDS = ("templates", "linear")


def smoothed_hs(hsv_window):
    """(hue, saturation): the smoothed 256-bin histograms (pixel counts) of the window's colour_region."""
    hue, sat = hs_histograms(colour_region(hsv_window))
    return smooth_histogram(hue), smooth_histogram(sat)


def colour_feature(hue_smoothed, sat_smoothed):
    """The linear colour classifier's input: both smoothed histograms normalised to a mean of 1 per bin."""
    scale = HS_BINS / max(float(hue_smoothed.sum()), 1e-9)
    return np.concatenate([hue_smoothed, sat_smoothed]).astype(np.float32) * np.float32(scale)


def prepare_colour_vectors(kind, vectors):
    """What colour_score compares with: templates smoothed once per half; linear weights as they are."""
    vectors = np.asarray(vectors, np.float32)
    if kind != "templates":
        return vectors
    return [(smooth_histogram(v[:HS_BINS]), smooth_histogram(v[HS_BINS:])) for v in vectors]


def colour_score(kind, prepared, bias, hue_smoothed, sat_smoothed):
    """A window's colour score against one imagery's colour model (higher = more like the species there).

    templates: the best, over the templates, mean of the hue and saturation Pearson correlations (paper
    eq. 6; one template = the paper's test); linear: weights . colour_feature + bias."""
    if kind == "templates":
        return max(0.5 * (pearson(hue_smoothed, hue) + pearson(sat_smoothed, sat)) for hue, sat in prepared)
    return float(np.dot(prepared[0], colour_feature(hue_smoothed, sat_smoothed))) + bias


def frame_colour(hsv):
    """A whole frame's hue+saturation histogram (512, each half normalised to sum 1): picks the nearest domain."""
    hue = cv2.calcHist([hsv], [0], None, [HS_BINS], [0, 256]).ravel()
    sat = cv2.calcHist([hsv], [1], None, [HS_BINS], [0, 256]).ravel()
    total = max(float(hue.sum()), 1.0)
    return np.concatenate([hue, sat]).astype(np.float32) / np.float32(total)


def frame_colour_similarity(colour_a, colour_b):
    """Mean hue and saturation Pearson correlation of two frame_colour histograms (smoothed)."""
    a_h, a_s = smooth_histogram(colour_a[:HS_BINS]), smooth_histogram(colour_a[HS_BINS:])
    b_h, b_s = smooth_histogram(colour_b[:HS_BINS]), smooth_histogram(colour_b[HS_BINS:])
    return 0.5 * (pearson(a_h, b_h) + pearson(a_s, b_s))
