# ForaNav tree detector: the feature definitions shared by training, the camera and the host tools.
#
# Runs on the JeVois-A33 (Python 3.7, numpy 1.16, OpenCV 4.10) and on the host. One definition of each
# feature lives here, so that a model trained on the host scores the same numbers on the camera.
#
# Paper section III-A (hierarchical HOG + colour check), per sliding window of W x W pixels:
#   top layer     the window's value channel downscaled to W_d = 24 px; HOG with 6 px cells, blocks of
#                 3x3 cells, block stride 1 cell, 9 unsigned orientation bins -> 2x2 blocks x 81 = 324 numbers,
#                 scored by a linear SVM (the star shape of the fronds);
#   bottom layer  the full-resolution value window; its global 9-bin orientation histogram (the sum of all
#                 its HOG cell histograms, per pixel), divided by the window's contrast; the variance plus
#                 squared mean of those 9 numbers must exceed a threshold (needle-like leaflets: much
#                 gradient per unit of contrast). The paper's raw variance is hog_global_variance; the
#                 detector uses hog_texture (see there why);
#   colour        hue and saturation histograms of the window's central region (foranav_colour).
#
# Conventions (host and camera alike):
# - HSV is OpenCV's COLOR_BGR2HSV_FULL: hue 0..255 covers the full circle (foranav_colour uses all 256).
# - Gradients use the [-1, 0, 1] kernel (paper eq. 1-2) with replicated borders.
# - Orientation is unsigned (0..180 deg). It is quantized to 256 levels of the full circle
#   (cv2.convertScaleAbs of the angle; 1.4 deg steps) and spread linearly over the two nearest of the 9 bins
#   with an 8-bit look-up table (weights in 1/255). The magnitude is quantized to 8 bits too
#   (MAGNITUDE_CODE_SCALE codes per grey level). A pixel's vote is the integer product code x weight, so
#   binning is table look-ups and 8/16-bit arithmetic on the camera, and the fast per-frame path and the
#   per-window reference count the same votes. Histograms are reported back in grey levels.
# - Blocks are L2-normalised (Dalal-Triggs' L2-norm with a small epsilon). L2-Hys clipping is left out on
#   purpose: without it, a linear SVM's score is linear in the cell histograms divided by one norm per block,
#   which lets the detector score every window of a frame at once.
import cv2
import numpy as np

HOG_WINDOW = 24  # W_d: top-layer window side after downscaling, pixels
HOG_CELL = 6  # C: cell side, pixels
HOG_BLOCK = 3  # B: block side, cells
HOG_BLOCK_STRIDE = 1  # S: block stride, cells
HOG_BINS = 9  # n: unsigned orientation bins over 0..180 deg
BLOCK_NORM_EPS = 1.0  # added in quadrature to a block's L2 norm (grey levels); keeps flat blocks near 0
ANGLE_LEVELS = 256  # orientation quantization levels over 0..360 deg


def _soft_bin_table(n_bins=HOG_BINS, levels=ANGLE_LEVELS):
    """(levels, n_bins) float32: weight of each bin for each quantized angle level (linear interpolation)."""
    degrees = (np.arange(levels) * 360.0 / levels) % 180.0
    bin_width = 180.0 / n_bins
    position = degrees / bin_width - 0.5  # bin centres at (k + 0.5) * bin_width
    lower = np.floor(position)
    upper_weight = position - lower
    table = np.zeros((levels, n_bins), np.float32)
    rows = np.arange(levels)
    table[rows, lower.astype(int) % n_bins] += (1.0 - upper_weight).astype(np.float32)
    table[rows, (lower.astype(int) + 1) % n_bins] += upper_weight.astype(np.float32)
    return table


SOFT_BIN_TABLE = _soft_bin_table()
SOFT_BIN_TABLE_U8 = np.round(SOFT_BIN_TABLE * 255.0).astype(np.uint8)  # votes in 1/255
_SOFT_BIN_TABLE_F32 = SOFT_BIN_TABLE_U8.astype(np.float32)
MAGNITUDE_CODE_SCALE = 0.7  # magnitude codes per grey level: the largest [-1,0,1] magnitude, 360.6, -> 252
VOTE_UNIT = 1.0 / (255.0 * MAGNITUDE_CODE_SCALE)  # grey levels per unit of code x weight


def bgr_to_hsv(bgr):
    """The project's HSV: cv2.COLOR_BGR2HSV_FULL (hue 0..255 for the full circle)."""
    return cv2.cvtColor(bgr, cv2.COLOR_BGR2HSV_FULL)


def gradient_levels(gray):
    """8-bit gradient magnitude code and quantized orientation level of every pixel: (code, level), uint8.

    [-1, 0, 1] kernels with replicated borders, as in the paper's equations (1)-(2); code = magnitude x
    MAGNITUDE_CODE_SCALE rounded; level = angle x 256/360 rounded (360 deg saturates at 255 = 358.6 deg).
    """
    gx = cv2.Sobel(gray, cv2.CV_32F, 1, 0, ksize=1, borderType=cv2.BORDER_REPLICATE)
    gy = cv2.Sobel(gray, cv2.CV_32F, 0, 1, ksize=1, borderType=cv2.BORDER_REPLICATE)
    magnitude, angle = cv2.cartToPolar(gx, gy, angleInDegrees=True)
    codes = cv2.convertScaleAbs(magnitude, alpha=MAGNITUDE_CODE_SCALE)
    levels = cv2.convertScaleAbs(angle, alpha=ANGLE_LEVELS / 360.0)
    return codes, levels


def orientation_histogram(codes, levels):
    """Magnitude-weighted 9-bin histogram (float64, grey levels) of the given pixels."""
    per_level = np.bincount(levels.ravel(), weights=codes.ravel().astype(np.float64), minlength=ANGLE_LEVELS)
    return per_level.dot(SOFT_BIN_TABLE_U8.astype(np.float64)) * VOTE_UNIT


# ---------------------------------------------------------------------------------------------------------
# Bottom layer


def global_orientation_histogram(value_window_uint8):
    """The bottom layer's global 9-bin HOG histogram: the sum of all cell histograms of the full-resolution
    window, divided by its pixel count (grey levels of gradient per pixel per bin)."""
    value = np.asarray(value_window_uint8)
    if value.ndim != 2 or value.size == 0:
        raise ValueError("value window must be a non-empty 2-D array")
    codes, levels = gradient_levels(value)
    return orientation_histogram(codes, levels) / float(value.size)


def hog_global_variance(value_window_uint8):
    """Var_hog (paper eq. 5): population variance of the bottom layer's global 9-bin histogram.

    Units: (grey levels per pixel)^2. Fine, needle-like texture carries much gradient energy, so oil palm
    crowns score high; smooth crowns and flat ground score low.
    """
    return float(np.var(global_orientation_histogram(value_window_uint8)))


TEXTURE_CONTRAST_FLOOR = 4.0  # grey levels added to the window's contrast: flat windows stay near 0


def hog_texture(value_window_uint8):
    """The detector's bottom-layer cue: Var_hog of the contrast-normalised global histogram + its squared mean.

    The global 9-bin histogram h (grey levels of gradient per pixel) is divided by the window's contrast
    (standard deviation of its values + TEXTURE_CONTRAST_FLOOR), and the cue is the mean of the squared
    bins: Var(h') + mean(h')^2, in 1/px^2. Why not the paper's Var_hog of h alone: it scales with the square
    of the gradient energy, so it collapses for dim or blurred crowns (the JeVois frame at 352x288 with
    0.6 px blur) and a blurred oil palm falls to a coconut's value. Dividing by the contrast removes the
    light and camera gain; keeping the mean keeps what the needle-like leaflets really add under blur: much
    gradient per unit of contrast (a fine texture). Measured on 40 rendered specimens per class with the
    sensor effects (ROC AUC oil palm vs coconut / date palm): Var_hog 0.85 / 0.96, this cue 1.00 / 0.98;
    at gain 0.75 as well: 0.83 / 0.95 vs 1.00 / 0.98; sharp renders: 1.00 / 1.00 for both. The floor keeps
    near-flat windows (sensor noise only) from scoring high.
    """
    value = np.asarray(value_window_uint8)
    histogram = global_orientation_histogram(value)
    contrast = float(cv2.meanStdDev(value)[1][0, 0]) + TEXTURE_CONTRAST_FLOOR
    normalised = histogram / contrast
    return float(normalised.dot(normalised) / normalised.size)


# ---------------------------------------------------------------------------------------------------------
# Top layer


def hog_descriptor_length(window=HOG_WINDOW, cell=HOG_CELL, block=HOG_BLOCK, stride=HOG_BLOCK_STRIDE,
                          bins=HOG_BINS):
    """Descriptor length: blocks per side squared x cells per block x bins (324 for the paper's values)."""
    cells = window // cell
    blocks = (cells - block) // stride + 1
    return blocks * blocks * block * block * bins


def downscale_value(value, window):
    """The value image scaled by W_d / W with area averaging (the top layer's input)."""
    scale = HOG_WINDOW / float(window)
    return cv2.resize(value, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)


def top_layer_hog(small_value):
    """Top-layer HOG descriptor (324 float32) of one downscaled value window.

    ``small_value`` is W_d x W_d, or (W_d + 2) x (W_d + 2) with one pixel of context on each side so that
    the border gradients see the neighbouring pixels (as when the whole frame is processed at once).
    Order: block row, block column, cell row in block, cell column in block, bin.
    """
    small_value = np.asarray(small_value)
    side = small_value.shape[0]
    if small_value.shape != (side, side) or side not in (HOG_WINDOW, HOG_WINDOW + 2):
        raise ValueError("top-layer window must be %dx%d or %dx%d" % (HOG_WINDOW, HOG_WINDOW,
                                                                      HOG_WINDOW + 2, HOG_WINDOW + 2))
    codes, levels = gradient_levels(small_value)
    if side == HOG_WINDOW + 2:
        codes, levels = codes[1:-1, 1:-1], levels[1:-1, 1:-1]
    n_cells = HOG_WINDOW // HOG_CELL
    cells = np.zeros((n_cells, n_cells, HOG_BINS))
    for row in range(n_cells):
        for col in range(n_cells):
            rows = slice(row * HOG_CELL, (row + 1) * HOG_CELL)
            cols = slice(col * HOG_CELL, (col + 1) * HOG_CELL)
            cells[row, col] = orientation_histogram(codes[rows, cols], levels[rows, cols])
    n_blocks = (n_cells - HOG_BLOCK) // HOG_BLOCK_STRIDE + 1
    blocks = []
    for row in range(n_blocks):
        for col in range(n_blocks):
            r0, c0 = row * HOG_BLOCK_STRIDE, col * HOG_BLOCK_STRIDE
            block = cells[r0:r0 + HOG_BLOCK, c0:c0 + HOG_BLOCK].ravel()
            blocks.append(block / np.sqrt(block.dot(block) + BLOCK_NORM_EPS ** 2))
    return np.concatenate(blocks).astype(np.float32)


SECOND_STAGE_WINDOWS = (48,)  # side of the second stage's downscaled window (multiples of HOG_CELL)


def second_stage_hog(value_window, side):
    """HOG of one full-resolution value window downscaled to side x side (the second stage's descriptor):
    the top layer's cells, blocks, bins and norms at twice its resolution, so the leaflets of a crown and
    the gap to its neighbours show. Length hog_descriptor_length(side) (2916 for 48)."""
    return _hog_of_downscaled(_downscaled(value_window, side))


def _downscaled(value_window, side):
    """The value window resized to the second stage's side x side (checked: whole cells, at least a block)."""
    if side % HOG_CELL or side < HOG_BLOCK * HOG_CELL:
        raise ValueError("second-stage window must be a multiple of %d px, at least %d"
                         % (HOG_CELL, HOG_BLOCK * HOG_CELL))
    return cv2.resize(np.asarray(value_window), (side, side), interpolation=cv2.INTER_AREA)


def _hog_of_downscaled(small):
    side = small.shape[0]
    codes, levels = gradient_levels(cv2.copyMakeBorder(small, 1, 1, 1, 1, cv2.BORDER_REPLICATE))
    codes, levels = codes[1:-1, 1:-1], levels[1:-1, 1:-1]
    n_cells = side // HOG_CELL
    # cell histograms of all cells at once: per-pixel soft votes, summed over each cell
    votes = _SOFT_BIN_TABLE_F32[levels] * codes.astype(np.float32)[:, :, None]
    cells = votes.reshape(n_cells, HOG_CELL, n_cells, HOG_CELL, HOG_BINS).sum(axis=(1, 3)) * VOTE_UNIT
    n_blocks = (n_cells - HOG_BLOCK) // HOG_BLOCK_STRIDE + 1
    blocks = np.empty((n_blocks, n_blocks, HOG_BLOCK, HOG_BLOCK, HOG_BINS), np.float32)
    for r in range(HOG_BLOCK):
        for c in range(HOG_BLOCK):
            blocks[:, :, r, c] = cells[r:r + n_blocks * HOG_BLOCK_STRIDE:HOG_BLOCK_STRIDE,
                                       c:c + n_blocks * HOG_BLOCK_STRIDE:HOG_BLOCK_STRIDE]
    blocks = blocks.reshape(n_blocks * n_blocks, -1)
    norms = np.sqrt((blocks * blocks).sum(axis=1) + BLOCK_NORM_EPS ** 2)
    return (blocks / norms[:, None]).ravel().astype(np.float32)


# The second stage's optional radial cue: how a window's gradients lie against the lines from its centre, ring
# by ring. A palm's fronds radiate from the crown's centre, so in a window centred on a crown the leaflet edges
# run along those lines; in a window between crowns or off a crown's centre they do not. Rotation- and
# flip-invariant, so a few crowns teach it, where the HOG's 2916 per-cell weights need many.
SECOND_STAGE_KINDS = ("hog", "hog+radial")
SECOND_STAGE_VIEWS = (1, 4)  # the window as it is, or the mean over its four quarter turns
RADIAL_RINGS = 5  # four rings of equal width inside the inscribed circle, and the corners outside it
RADIAL_BINS = 6  # angle between a gradient and the radial line, 0..90 deg
RADIAL_LENGTH = RADIAL_RINGS * RADIAL_BINS + 2 * RADIAL_RINGS
# The cue's values are shares (0..1), of the size of the HOG's block-normalised values, and 40 of them stand
# against 2916: scaled up, the SVM's regulariser lets them weigh (gain 1 / 3 / 10 on a split of the training
# side of ../shared/data/real: mean frame F1 of Google Earth and Kluang 74.4 / 75.5 / 73.0 %).
RADIAL_GAIN = 3.0


_RADIAL_GEOMETRY = {}


def _radial_geometry(side):
    """(ring index, unit radial x, unit radial y) per pixel of a side x side window (cached)."""
    if side not in _RADIAL_GEOMETRY:
        centre = (side - 1) / 2.0
        ys, xs = np.mgrid[0:side, 0:side].astype(np.float32) - np.float32(centre)
        radius = np.sqrt(xs * xs + ys * ys)
        ring = np.minimum((radius / (side / 2.0) * (RADIAL_RINGS - 1)).astype(np.int32), RADIAL_RINGS - 1)
        safe = np.maximum(radius, 0.5)
        _RADIAL_GEOMETRY[side] = (ring, xs / safe, ys / safe)
    return _RADIAL_GEOMETRY[side]


def radial_descriptor(small_value):
    """RADIAL_LENGTH values of a square value window (already downscaled): per ring, the magnitude-weighted
    histogram of the angle between gradient and radial line (each ring's histogram sums to 1), each ring's
    share of the window's gradient, and each ring's mean value against the window's (contrast-free)."""
    small = np.asarray(small_value, np.float32)
    side = small.shape[0]
    ring, ux, uy = _radial_geometry(side)
    gx = cv2.Sobel(small, cv2.CV_32F, 1, 0, ksize=1, borderType=cv2.BORDER_REPLICATE)
    gy = cv2.Sobel(small, cv2.CV_32F, 0, 1, ksize=1, borderType=cv2.BORDER_REPLICATE)
    magnitude = np.sqrt(gx * gx + gy * gy)
    along = np.abs(gx * ux + gy * uy) / np.maximum(magnitude, 1e-6)  # |cos| of the angle to the radial line
    angle_bin = np.minimum((np.arccos(np.minimum(along, 1.0)) / (np.pi / 2) * RADIAL_BINS).astype(np.int32),
                           RADIAL_BINS - 1)
    cells = (ring * RADIAL_BINS + angle_bin).ravel()
    hist = np.bincount(cells, weights=magnitude.ravel().astype(np.float64),
                       minlength=RADIAL_RINGS * RADIAL_BINS).reshape(RADIAL_RINGS, RADIAL_BINS)
    ring_energy = hist.sum(axis=1)
    shape = hist / np.maximum(ring_energy, 1e-6)[:, None]
    share = ring_energy / max(ring_energy.sum(), 1e-6)
    pixels = np.bincount(ring.ravel(), minlength=RADIAL_RINGS).astype(np.float64)
    ring_mean = np.bincount(ring.ravel(), weights=small.ravel().astype(np.float64), minlength=RADIAL_RINGS)
    ring_mean = ring_mean / np.maximum(pixels, 1.0)
    spread = max(float(small.std()), 1.0)
    profile = (ring_mean - float(small.mean())) / spread
    return (np.concatenate([shape.ravel(), share, profile]) * RADIAL_GAIN).astype(np.float32)


def second_stage_length(side, kind="hog"):
    """Length of the second stage's descriptor of the given kind."""
    return hog_descriptor_length(side) + (RADIAL_LENGTH if kind == "hog+radial" else 0)


def second_stage_descriptor(value_window, side, kind="hog", views=1):
    """The second stage's descriptor of one full-resolution value window: its HOG at side px and, for kind
    "hog+radial", the radial cue of the same downscaled window. views 4: the HOG is the mean of the HOGs of
    the downscaled window's four quarter turns (a crown seen from straight above has no "up", so a linear
    score of the mean is the mean score over the turns; the radial cue is turn-invariant already)."""
    if kind not in SECOND_STAGE_KINDS:
        raise ValueError("second-stage kind %r is not one of %s" % (kind, ", ".join(SECOND_STAGE_KINDS)))
    if views not in SECOND_STAGE_VIEWS:
        raise ValueError("second-stage views %r is not one of %s" % (views, SECOND_STAGE_VIEWS))
    small = _downscaled(value_window, side)
    hog = _hog_of_downscaled(small) if views == 1 else _mean_hog_of_turns(small, views)
    if kind == "hog":
        return hog
    return np.concatenate([hog, radial_descriptor(small)])


def _mean_hog_of_turns(small, turns):
    """The mean HOG of the first `turns` quarter turns of a downscaled window (summed in float64, in order:
    the same bytes on the camera's numpy as on the host's)."""
    total = np.zeros(hog_descriptor_length(small.shape[0]), np.float64)
    for turn in range(turns):
        total += _hog_of_downscaled(np.ascontiguousarray(np.rot90(small, turn)))
    return (total / turns).astype(np.float32)


def window_with_context(value, x0, y0, window):
    """The top layer's input for the window at (x0, y0) of a full-resolution value image: the window plus one
    downscaled pixel of context per side, downscaled to (W_d + 2)^2; where the frame ends, the window's own
    border pixels are replicated (as cv2.Sobel does on a whole downscaled frame).

    x0, y0 and the context are rounded to whole pixels; for windows that are a multiple of W_d and origins
    on the W / W_d grid this equals cropping ``downscale_value(value, window)`` with one pixel around.
    """
    pad = int(round(window / float(HOG_WINDOW)))
    x0, y0, side = int(round(x0)), int(round(y0)), int(round(window))
    height, width = value.shape[:2]
    if x0 < 0 or y0 < 0 or x0 + side > width or y0 + side > height:  # window leaves the frame: replicate it
        x_lo, y_lo = max(0, x0), max(0, y0)
        x_hi, y_hi = min(width, x0 + side), min(height, y0 + side)
        if x_lo >= x_hi or y_lo >= y_hi:
            raise ValueError("window lies outside the frame")
        inside = cv2.copyMakeBorder(value[y_lo:y_hi, x_lo:x_hi], y_lo - y0, y0 + side - y_hi, x_lo - x0,
                                    x0 + side - x_hi, cv2.BORDER_REPLICATE)
        return window_with_context(inside, 0, 0, side)
    left, top = int(x0 - pad >= 0), int(y0 - pad >= 0)
    right, bottom = int(x0 + side + pad <= width), int(y0 + side + pad <= height)
    crop = value[y0 - pad * top:y0 + side + pad * bottom, x0 - pad * left:x0 + side + pad * right]
    small = cv2.resize(crop, (HOG_WINDOW + left + right, HOG_WINDOW + top + bottom), interpolation=cv2.INTER_AREA)
    return cv2.copyMakeBorder(small, 1 - top, 1 - bottom, 1 - left, 1 - right, cv2.BORDER_REPLICATE)
