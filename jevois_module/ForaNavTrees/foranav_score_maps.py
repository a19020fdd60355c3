# ForaNav tree detector: the top layer's linear SVM score of every window of every size, from one atlas.
#
# The value channel is downscaled once per window size W (by W_d / W); the downscaled frames sit side by side
# in one atlas image, whose gradients, orientation votes, cell histograms (on a lattice of gcd(step, 6)
# downscaled pixels), block norms and SVM scores of EVERY window of every size are a dozen whole-image
# operations. Nothing is computed or allocated per window. A linear SVM with L2 block norms is linear in the
# cell histograms divided by one norm per block, which is what makes this possible (foranav_features).
# Camera and host alike (Python 3.7, numpy 1.16, OpenCV 4.10).
import math

import cv2
import numpy as np

import foranav_features as features


class ScalePlan(object):
    """Everything about one window size that depends only on the frame shape: computed once, reused."""

    def __init__(self, frame_height, frame_width, window, step):
        self.window = float(window)
        self.scale = features.HOG_WINDOW / self.window
        factor = int(round(self.window)) // features.HOG_WINDOW
        if factor * features.HOG_WINDOW == self.window:
            # Integer factor: crop to whole blocks so that every downscaled pixel is an exact block mean
            # (cv2's INTER_AREA fast path) and any window equals its own crop, downscaled.
            self.crop_height = frame_height // factor * factor
            self.crop_width = frame_width // factor * factor
        else:
            self.crop_height, self.crop_width = frame_height, frame_width
        probe = cv2.resize(np.zeros((self.crop_height, self.crop_width), np.uint8), None, fx=self.scale,
                           fy=self.scale, interpolation=cv2.INTER_AREA)
        self.small_height, self.small_width = probe.shape
        self.lattice = math.gcd(step, features.HOG_CELL)  # cell histograms are computed every `lattice` px
        self.stride = step // self.lattice  # window step in lattice units
        cell = features.HOG_CELL // self.lattice  # one cell in lattice units
        cells_per_window = features.HOG_WINDOW // features.HOG_CELL
        self.map_height = self.small_height // self.lattice - cells_per_window * cell + 1
        self.map_width = self.small_width // self.lattice - cells_per_window * cell + 1
        self.usable = self.map_height > 0 and self.map_width > 0
        self.atlas_row = self.atlas_col = 0  # where the downscaled frame sits in the atlas (set by Atlas)

    def window_origin(self, row, col):
        """Frame-pixel origin (x0, y0) of the window at (row, col) of this size's score map."""
        unit = self.stride * self.lattice / self.scale
        return col * unit, row * unit


class Atlas(object):
    """One image holding every window size's downscaled frame side by side, each with a one-pixel
    replicated border, so that gradients, orientation binning, cell histograms, block norms and scores are
    computed once per frame for all sizes (a dozen whole-image operations instead of a dozen per size).
    Each downscaled frame starts on the lattice, so its windows are a plain slice of the atlas' score map."""

    def __init__(self, plans):
        self.plans = [p for p in plans if p.usable]
        g = self.plans[0].lattice
        col = 0
        for plan in self.plans:
            plan.atlas_row = g  # room for the border row above, on the lattice
            plan.atlas_col = round_up(col + 1, g)
            col = plan.atlas_col + plan.small_width + 1
        height = round_up(g + max(p.small_height for p in self.plans) + 1, g)
        width = round_up(col, g)
        self.image = np.zeros((height, width), np.uint8)
        self.lattice = g
        self.cell = features.HOG_CELL // g
        # Work buffers, reused every frame (fresh megabyte-sized arrays would cost page faults each frame).
        # Per-bin data is planar, one (height, width) image per bin: single-channel look-ups, products and
        # block means are several times faster than on a 9-channel interleaved image.
        bins = features.HOG_BINS
        self.weights = np.empty((bins, height, width), np.uint8)
        self.votes = np.empty((bins, height, width), np.uint16)
        self.lattice_votes = np.empty((bins * height // g, width // g), np.uint16)

    def fill(self, value):
        for plan in self.plans:
            small = cv2.resize(value[:plan.crop_height, :plan.crop_width], None, fx=plan.scale, fy=plan.scale,
                               interpolation=cv2.INTER_AREA)
            self.image[plan.atlas_row - 1:plan.atlas_row + plan.small_height + 1,
                       plan.atlas_col - 1:plan.atlas_col + plan.small_width + 1] = cv2.copyMakeBorder(
                small, 1, 1, 1, 1, cv2.BORDER_REPLICATE)
        return self.image

    def split(self, scores):
        """[(plan, score map)] from the atlas' score map."""
        g = self.lattice
        out = []
        for plan in self.plans:
            row, col = plan.atlas_row // g, plan.atlas_col // g
            region = scores[row:row + plan.map_height:plan.stride, col:col + plan.map_width:plan.stride]
            out.append((plan, np.ascontiguousarray(region)))
        return out



class WindowScorer(object):
    """A model's top-layer SVM, regrouped for scoring whole atlases: weights as (bin, block row, block col,
    cell row, cell col), one soft-binning table per bin."""

    def __init__(self, svm_weights, svm_bias):
        blocks = (features.HOG_WINDOW // features.HOG_CELL - features.HOG_BLOCK) // features.HOG_BLOCK_STRIDE + 1
        self.blocks = blocks
        weights = np.asarray(svm_weights).reshape(blocks, blocks, features.HOG_BLOCK, features.HOG_BLOCK,
                                                  features.HOG_BINS)
        self.cell_weights = np.ascontiguousarray(
            weights.transpose(4, 0, 1, 2, 3).reshape(features.HOG_BINS, -1)).astype(np.float32)
        self.bias = svm_bias
        self.bin_tables = [np.ascontiguousarray(features.SOFT_BIN_TABLE_U8[:, b]) for b in range(features.HOG_BINS)]

    def scores(self, atlas):
        """Linear SVM score of the window at every lattice position of the atlas (g px apart; o = lattice
        units per cell).

        With cell histograms H on the lattice, block norms N and the weights w regrouped per (block, cell):
            score(p) = bias + sum_blocks [ sum_cells w_{block,cell} . H(p + block + cell) ] / N(p + block)
        computed as a few whole-image operations.
        """
        g, o, bins, k, n = atlas.lattice, atlas.cell, features.HOG_BINS, features.HOG_BLOCK, self.blocks
        codes, levels = features.gradient_levels(atlas.image)
        for b in range(bins):  # each pixel's vote for bin b: magnitude code x soft-binning weight (uint16)
            cv2.LUT(levels, self.bin_tables[b], dst=atlas.weights[b])
            cv2.multiply(atlas.weights[b], codes, dst=atlas.votes[b], dtype=cv2.CV_16U)
        height, width = atlas.image.shape
        if g > 1:  # mean votes over g x g pixels (exact block mean): the lattice the cells are added from
            votes = cv2.resize(atlas.votes.reshape(bins * height, width), (width // g, bins * height // g),
                               dst=atlas.lattice_votes, interpolation=cv2.INTER_AREA)
            votes = votes.reshape(bins, height // g, width // g)
        else:
            votes = atlas.votes
        planes = votes.astype(np.float32)
        planes *= g * g * features.VOTE_UNIT
        cells = box_sum(planes, o)  # cell histograms at every lattice position: (bins, rows, cols)
        # Block norms: sum of squared cell histograms over k x k cells, one map.
        energy = box_sum(np.einsum("bij,bij->ij", cells, cells), o, k, step=o)
        inverse_norm = 1.0 / np.sqrt(energy + features.BLOCK_NORM_EPS ** 2)
        # Per (block, cell) responses w . H as maps (block row, block col, cell row, cell col, rows, cols),
        # then summed over the cells of each block.
        rows, cols = cells.shape[1], cells.shape[2]
        responses = self.cell_weights.T.dot(cells.reshape(bins, -1)).reshape(n, n, k, k, rows, cols)
        width = cols - (k - 1) * o
        row_sum = responses[:, :, :, 0, :, 0:width].copy()
        for c in range(1, k):
            row_sum += responses[:, :, :, c, :, c * o:c * o + width]
        height = rows - (k - 1) * o
        block_sum = row_sum[:, :, 0, 0:height, :].copy()
        for r in range(1, k):
            block_sum += row_sum[:, :, r, r * o:r * o + height, :]
        # Window score: blocks at offsets (by, bx) x block stride.
        bs = features.HOG_BLOCK_STRIDE * o
        map_height = height - (n - 1) * bs
        map_width = width - (n - 1) * bs
        scores = np.full((map_height, map_width), self.bias, np.float32)
        for by in range(n):
            for bx in range(n):
                rows = slice(by * bs, by * bs + map_height)
                cols = slice(bx * bs, bx * bs + map_width)
                scores += block_sum[by, bx, rows, cols] * inverse_norm[rows, cols]
        return scores



def round_up(value, multiple):
    return -(-value // multiple) * multiple


def box_sum(array, size, count=None, step=1):
    """Sums over the last two axes of `count` entries spaced `step` apart (default: `size` consecutive)."""
    if count is None:
        count, step = size, 1
    span = (count - 1) * step
    height = array.shape[-2] - span
    width = array.shape[-1] - span
    rows = array[..., 0:height, :].copy()
    for i in range(1, count):
        rows += array[..., i * step:i * step + height, :]
    out = rows[..., 0:width].copy()
    for j in range(1, count):
        out += rows[..., j * step:j * step + width]
    return out

