# ForaNav tree detector: the model file, one definition for training (host) and deployment (camera).
#
# A model is a plain .npz of arrays, loaded with allow_pickle=False, so numpy 1.16 on the JeVois-A33 reads
# what numpy 2 on the host wrote. Strings are fixed-width unicode arrays; every scalar is a 0-d array.
# The file carries everything that must not drift between training and deployment: the HOG configuration
# (checked against foranav_features on load), the linear SVM, the three thresholds, the colour template,
# the species and the window sizes.
#
# Keys (format version 2; version 1 held the raw Var_hog as variance_threshold):
#   format_version   int      FORMAT_VERSION; a file of another version is refused with a clear message
#   species          str      e.g. "oil_palm" (also the id of N2 serial lines)
#   hog_config       int[7]   W_d, cell, block, block stride, bins, angle levels, block-norm eps (x1000)
#   svm_kind         str      "linear": score = weights . descriptor + bias
#   svm_weights      f32[324] top-layer descriptor weights
#   svm_bias         f32
#   svm_threshold    f32      a window is a candidate when its score exceeds this
#   variance_threshold f32    bottom-layer cue foranav_features.hog_texture must exceed this (1/px^2)
#   hs_threshold     f32      mean hue/saturation Pearson correlation must exceed this
#   edge_threshold   f32      SVM score a peak on a score map's border (window at the frame edge) must exceed
#   template_hue     f32[256] hue histogram of the species (normalised to sum 1)
#   template_sat     f32[256] saturation histogram of the species (normalised to sum 1)
#   window_sizes     int[k]   sliding-window sides W in pixels of the training frames' resolution
#   window_margin    f32      window side / crown diameter used in training (box size = W / margin)
#   reference_width  int      frame width the window sizes refer to (they scale with the frame width)
#   seed             int      training seed (provenance)
#   notes            str      free text: data, counts, figures (provenance)
import numpy as np

import foranav_features as features

FORMAT_VERSION = 2
DEFAULT_EDGE_THRESHOLD = 0.0  # the SVM's decision boundary (models built in code; training calibrates it)
SVM_KINDS = ("linear",)
_EPS_SCALE = 1000.0
REQUIRED_KEYS = ("format_version", "species", "hog_config", "svm_kind", "svm_weights", "svm_bias",
                 "svm_threshold", "variance_threshold", "hs_threshold", "edge_threshold", "template_hue",
                 "template_sat", "window_sizes", "window_margin", "reference_width", "seed", "notes")


class ModelFormatError(ValueError):
    """The file is not a ForaNav model this code can use (message names the file and the problem)."""


def current_hog_config():
    return np.array([features.HOG_WINDOW, features.HOG_CELL, features.HOG_BLOCK, features.HOG_BLOCK_STRIDE,
                     features.HOG_BINS, features.ANGLE_LEVELS,
                     int(round(features.BLOCK_NORM_EPS * _EPS_SCALE))], np.int32)


class TreeModel(object):
    """A trained detector model (see the module comment for the meaning of each field)."""

    def __init__(self, species, svm_weights, svm_bias, svm_threshold, variance_threshold, hs_threshold,
                 template_hue, template_sat, window_sizes, window_margin, reference_width, seed=0, notes="",
                 edge_threshold=DEFAULT_EDGE_THRESHOLD):
        self.species = str(species)
        self.svm_weights = np.asarray(svm_weights, np.float32).ravel()
        self.svm_bias = float(svm_bias)
        self.svm_threshold = float(svm_threshold)
        self.variance_threshold = float(variance_threshold)
        self.hs_threshold = float(hs_threshold)
        self.edge_threshold = float(edge_threshold)
        self.template_hue = np.asarray(template_hue, np.float32).ravel()
        self.template_sat = np.asarray(template_sat, np.float32).ravel()
        self.window_sizes = tuple(int(w) for w in np.asarray(window_sizes).ravel())
        self.window_margin = float(window_margin)
        self.reference_width = int(reference_width)
        self.seed = int(seed)
        self.notes = str(notes)
        self.validate()

    def validate(self):
        length = features.hog_descriptor_length()
        if self.svm_weights.shape != (length,):
            raise ModelFormatError("svm_weights has %d values, the HOG descriptor has %d"
                                   % (self.svm_weights.size, length))
        for name in ("template_hue", "template_sat"):
            if getattr(self, name).shape != (features.HS_BINS,):
                raise ModelFormatError("%s must have %d bins" % (name, features.HS_BINS))
        if not self.window_sizes or min(self.window_sizes) < features.HOG_WINDOW:
            raise ModelFormatError("window_sizes must be non-empty and at least %d px" % features.HOG_WINDOW)
        if not self.species or len(self.species.split()) != 1:
            raise ModelFormatError("species must be one word")
        values = [self.svm_bias, self.svm_threshold, self.variance_threshold, self.hs_threshold,
                  self.edge_threshold, self.window_margin] + list(self.svm_weights)
        if not np.all(np.isfinite(values)) or self.window_margin <= 0 or self.reference_width <= 0:
            raise ModelFormatError("model numbers must be finite, margin and reference width positive")

    def score(self, descriptor):
        """SVM decision value of one top-layer descriptor (positive = tree-like)."""
        return float(np.dot(self.svm_weights, descriptor)) + self.svm_bias

    def to_arrays(self):
        return {
            "format_version": np.array(FORMAT_VERSION, np.int32),
            "species": np.array(self.species),  # fixed-width unicode, no pickle
            "hog_config": current_hog_config(),
            "svm_kind": np.array("linear"),
            "svm_weights": self.svm_weights,
            "svm_bias": np.array(self.svm_bias, np.float32),
            "svm_threshold": np.array(self.svm_threshold, np.float32),
            "variance_threshold": np.array(self.variance_threshold, np.float32),
            "hs_threshold": np.array(self.hs_threshold, np.float32),
            "edge_threshold": np.array(self.edge_threshold, np.float32),
            "template_hue": self.template_hue,
            "template_sat": self.template_sat,
            "window_sizes": np.array(self.window_sizes, np.int32),
            "window_margin": np.array(self.window_margin, np.float32),
            "reference_width": np.array(self.reference_width, np.int32),
            "seed": np.array(self.seed, np.int64),
            "notes": np.array(self.notes),
        }


def save_model(model, file_obj):
    """Write the model as an uncompressed .npz to a path or binary file object (use an atomic writer)."""
    np.savez(file_obj, **model.to_arrays())


def load_model(path):
    """Read a model file; raises ModelFormatError naming the file for anything unusable."""
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {key: data[key] for key in data.files}
    except (IOError, OSError, ValueError) as err:
        raise ModelFormatError("%s: not a readable model file (%s)" % (path, err))
    return model_from_arrays(arrays, path)


def model_from_arrays(arrays, name="model"):
    if "format_version" not in arrays:
        raise ModelFormatError("%s: not a ForaNav model (no format_version)" % name)
    version = int(arrays["format_version"])
    if version != FORMAT_VERSION:
        raise ModelFormatError("%s: model format version %d, this detector reads version %d (retrain it with "
                               "'foranav train')" % (name, version, FORMAT_VERSION))
    missing = [key for key in REQUIRED_KEYS if key not in arrays]
    if missing:
        raise ModelFormatError("%s: missing %s" % (name, ", ".join(missing)))
    if not np.array_equal(np.asarray(arrays["hog_config"]), current_hog_config()):
        raise ModelFormatError("%s: trained with HOG configuration %s, this detector uses %s"
                               % (name, list(arrays["hog_config"]), list(current_hog_config())))
    kind = str(arrays["svm_kind"])
    if kind not in SVM_KINDS:
        raise ModelFormatError("%s: SVM kind %r is not supported (only %s)" % (name, kind, ", ".join(SVM_KINDS)))
    try:
        return TreeModel(
            species=str(arrays["species"]), svm_weights=arrays["svm_weights"],
            svm_bias=float(arrays["svm_bias"]), svm_threshold=float(arrays["svm_threshold"]),
            variance_threshold=float(arrays["variance_threshold"]), hs_threshold=float(arrays["hs_threshold"]),
            edge_threshold=float(arrays["edge_threshold"]),
            template_hue=arrays["template_hue"], template_sat=arrays["template_sat"],
            window_sizes=arrays["window_sizes"], window_margin=float(arrays["window_margin"]),
            reference_width=int(arrays["reference_width"]), seed=int(arrays["seed"]), notes=str(arrays["notes"]))
    except ModelFormatError as err:
        raise ModelFormatError("%s: %s" % (name, err))
