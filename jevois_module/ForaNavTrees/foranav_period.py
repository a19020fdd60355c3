# ForaNav tree detector: the planting period of a frame, from its value channel. Camera and host alike.
#
# Palms stand on a grid (about 9 m, triangular), so the frame repeats itself at the distance between
# neighbouring crowns. The autocorrelation of the value channel, at low resolution, has its first peak away
# from zero lag there: for touching crowns that is about a crown, for spaced ones the spacing. The peak
# suppression of the period stage (foranav_grouping.group_by_centre) uses a radius tied to it, not to the
# window or crown size (Srestasathiern & Rakwatin 2014: the window from the semi-variogram).
#
# Cost: one resize, one Hann product, three DFTs at about 116 x 96 (58 x 48 zero-padded), and a radial
# maximum through one precomputed ordering (cached per frame shape). No per-pixel Python.
import math

import cv2
import numpy as np

ANALYSIS_SIDE = 48  # the low-resolution copy's shorter side, at least (288 px frames: 1/6; a 65 px crown: 11 px)
MIN_PROMINENCE = 0.08  # the peak must rise this far (autocorrelation, 1 = zero lag) above the dip before it
MIN_PEAK = 0.15  # ... and reach this value: a weaker repeat is texture, not a grid
HARMONIC_SHARE = 0.5  # the nearest peak within this share of the strongest is the period, not a multiple
MIN_OVERLAP = 0.25  # lags where the Hann windows overlap less than this are too noisy to trust


class PeriodEstimator(object):
    """The planting period in frame pixels of value-channel frames of one shape, or None when the frame
    shows no clear repeat (an isolated crown, bare ground). Keeps its per-shape tables between calls."""

    def __init__(self):
        self._tables = {}

    def estimate(self, value, min_px, max_px):
        """Period in frame pixels within [min_px, max_px], or None when no clear autocorrelation peak."""
        profile, lag_px = self.radial_profile(value)
        return period_from_profile(profile, lag_px, min_px, max_px)

    def radial_profile(self, value):
        """(profile, lag_px): the largest normalised autocorrelation of the frame at each integer radius of
        the low-resolution lag grid (1 = zero lag), and the frame pixels one radius step stands for."""
        tables = self._table(value.shape[0], value.shape[1])
        small = cv2.resize(value[:tables.crop_height, :tables.crop_width], (tables.width, tables.height),
                           interpolation=cv2.INTER_AREA).astype(np.float32)
        small -= float(small.mean())
        small *= tables.hann
        padded = np.zeros((tables.pad_height, tables.pad_width), np.float32)
        padded[:tables.height, :tables.width] = small
        autocorrelation = _circular_autocorrelation(padded)
        zero = float(autocorrelation[0, 0])
        if zero <= 0.0:  # a flat frame
            return np.zeros(1, np.float32), tables.lag_px
        unbiased = autocorrelation.ravel()[tables.lags] * tables.overlap_inverse / zero
        return np.maximum.reduceat(unbiased, tables.starts), tables.lag_px

    def _table(self, height, width):
        key = (height, width)
        if key not in self._tables:
            self._tables = {key: _LagTable(height, width)}  # one frame shape at a time: bounded memory
        return self._tables[key]


class _LagTable(object):
    """Per frame shape: the low-resolution size, its Hann window, and the lags of the half plane ordered by
    radius (indices into the padded autocorrelation), with the inverse of the windows' overlap at each."""

    def __init__(self, height, width):
        # an integer factor on a frame cropped to whole blocks: cv2's exact block-mean path, several times
        # faster than a fractional INTER_AREA resize
        self.factor = max(1, min(height, width) // ANALYSIS_SIDE)
        self.height, self.width = height // self.factor, width // self.factor
        self.crop_height, self.crop_width = self.height * self.factor, self.width * self.factor
        self.lag_px = float(self.factor)
        self.hann = cv2.createHanningWindow((self.width, self.height), cv2.CV_32F)
        self.pad_height = cv2.getOptimalDFTSize(2 * self.height)
        self.pad_width = cv2.getOptimalDFTSize(2 * self.width)
        padded = np.zeros((self.pad_height, self.pad_width), np.float32)
        padded[:self.height, :self.width] = self.hann
        overlap = _circular_autocorrelation(padded)
        overlap /= float(overlap[0, 0])
        rows, cols = np.mgrid[0:self.height, -(self.width - 1):self.width]  # half plane: dy >= 0
        radius = np.rint(np.sqrt(rows * rows + cols * cols)).astype(np.int64).ravel()
        index = (rows.ravel() * self.pad_width + cols.ravel() % self.pad_width)
        trusted = overlap.ravel()[index] >= MIN_OVERLAP
        radius, index = radius[trusted], index[trusted]
        order = np.argsort(radius, kind="mergesort")
        radius, self.lags = radius[order], index[order]
        self.overlap_inverse = (1.0 / overlap.ravel()[self.lags]).astype(np.float32)
        # every radius 0..max is present (the column dy = 0 holds them all), so starts are one per radius
        self.starts = np.searchsorted(radius, np.arange(int(radius[-1]) + 1))


def _circular_autocorrelation(padded):
    """Circular autocorrelation of a zero-padded image: the inverse DFT of its power spectrum (packed CCS
    spectra throughout, the real-input half of the work)."""
    spectrum = cv2.dft(padded)
    power = cv2.mulSpectrums(spectrum, spectrum, 0, conjB=True)
    return cv2.dft(power, flags=cv2.DFT_INVERSE | cv2.DFT_REAL_OUTPUT | cv2.DFT_SCALE)


def period_from_profile(profile, lag_px, min_px, max_px):
    """The lag (frame px) of the nearest clear peak of the radial profile within [min_px, max_px] (rising
    MIN_PROMINENCE above the lowest value between zero lag and it, reaching MIN_PEAK and HARMONIC_SHARE of
    the strongest clear peak), refined by a parabola; None when there is none."""
    low = max(1, int(math.floor(min_px / lag_px)))
    high = min(len(profile) - 2, int(math.ceil(max_px / lag_px)))
    if high < low:
        return None
    peaks = []  # (radius, value) of the clear peaks, nearest first
    dip = float(profile[:low + 1].min())
    for r in range(low, high + 1):
        here = float(profile[r])
        dip = min(dip, here)
        if here >= profile[r - 1] and here >= profile[r + 1] and here - dip >= MIN_PROMINENCE and here >= MIN_PEAK:
            peaks.append((r, here))
    if not peaks:
        return None
    # a grid repeats at every multiple of its period, as strongly: the nearest strong peak is the period
    strongest = max(value for _r, value in peaks)
    best, best_value = next((r, value) for r, value in peaks if value >= HARMONIC_SHARE * strongest)
    before, after = float(profile[best - 1]), float(profile[best + 1])
    curvature = before - 2.0 * best_value + after
    offset = 0.0 if curvature >= 0 else max(-0.5, min(0.5, 0.5 * (before - after) / curvature))
    return (best + offset) * lag_px
