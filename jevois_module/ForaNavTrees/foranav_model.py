# ForaNav tree detector: the model file, one definition for training (host) and deployment (camera).
#
# A model is a plain .npz of arrays, loaded with allow_pickle=False, so numpy 1.16 on the JeVois-A33 reads
# what numpy 2 on the host wrote. Strings are fixed-width unicode arrays; every scalar is a 0-d array.
# The file carries everything that must not drift between training and deployment: the HOG configuration
# (checked against foranav_features on load), the one linear SVM, and per imagery ("domain": the photographs
# of one camera, light and place) a colour model and the three thresholds; the species, window sizes and
# the window/crown ratios.
#
# Keys (format version 3; version 2 held one colour template and one set of thresholds for all imagery):
#   format_version   int      FORMAT_VERSION; a file of another version is refused with a clear message
#   species          str      e.g. "oil_palm" (also the id of N2 serial lines)
#   hog_config       int[7]   W_d, cell, block, block stride, bins, angle levels, block-norm eps (x1000)
#   svm_kind         str      "linear": score = weights . descriptor + bias
#   svm_weights      f32[324] top-layer descriptor weights
#   svm_bias         f32
#   edge_threshold   f32      SVM score a peak on a score map's border (window at the frame edge) must exceed
#   colour_kind      str      "templates": similarity = best mean hue/saturation Pearson correlation with the
#                             domain's templates; "linear": a linear classifier on the histograms
#                             (foranav_features.colour_score)
#   domain_names     str[D]   one name per imagery (D >= 1), e.g. the training CSV's folder
#   colour_vectors   f32[D,K,512]  templates: K hue(256)+saturation(256) histograms (each half sums to 1);
#                             linear: K = 1 weight vector
#   colour_bias      f32[D]   linear: the classifier's bias (templates: 0)
#   frame_colour     f32[D,512]  mean whole-frame hue+saturation histogram of the domain's training frames
#                             (the detector picks the nearest domain of a frame by it when none is set)
#   svm_threshold    f32[D]   a window is a candidate when its score exceeds this
#   hs_threshold     f32[D]   colour score a detection must exceed
#   variance_threshold f32[D] bottom-layer cue foranav_features.hog_texture must exceed this (1/px^2)
#   window_sizes     int[k]   sliding-window sides W in pixels of the training frames' resolution (camera)
#   window_margin    f32      window side / crown diameter of the training windows (box size = W / margin)
#   reference_width  int      frame width the window sizes refer to (they scale with the frame width)
#   crown_ratios     f32[k]   window sides / typical crown diameter for whole-frame detection when the crown
#                             size in pixels is given (foranav detect --crown-px), calibrated on frames
#   seed             int      training seed (provenance)
#   notes            str      free text: data, counts, figures (provenance)
#   provenance       str      sources and licences of the training imagery
# Optional (all four or none; survey models): the second stage, a linear SVM on a finer HOG and the radial cue
# (foranav_features.second_stage_descriptor) that each group's best window must also pass.
#   second_window    int      side of its downscaled window (48)
#   second_weights   f32[n]   its weights (n = second_stage_length(second_window, second_kind))
#   second_bias      f32
#   second_threshold f32[D]   per domain, the score a detection's window must exceed
#   second_kind      str      optional: "hog+radial" adds the radial cue to the HOG (absent: "hog")
#   second_views     int      optional: 4 scores the mean HOG of the window's four quarter turns (absent: 1)
# Optional (all three or none; `train --cnn`): the learned stage, a small network (foranav_cnn).
#   cnn_onnx         u8[n]    the network in ONNX form (its bytes)
#   cnn_side         int      side of its square input, pixels (foranav_cnn.CNN_SIDE)
#   cnn_threshold    f32[D]   per domain, the logit a detection's window must exceed
import zipfile

import numpy as np

import foranav_colour as colours
import foranav_features as features

FORMAT_VERSION = 3
DEFAULT_EDGE_THRESHOLD = 0.0  # the SVM's decision boundary (models built in code; training calibrates it)
SVM_KINDS = ("linear",)
_EPS_SCALE = 1000.0
# numpy dtype kinds each field may have: f float, i/u integer, U text
FIELD_KINDS = {"format_version": "iu", "species": "U", "hog_config": "iu", "svm_kind": "U", "svm_weights": "fiu",
               "svm_bias": "fiu", "edge_threshold": "fiu", "colour_kind": "U", "domain_names": "U",
               "colour_vectors": "fiu", "colour_bias": "fiu", "frame_colour": "fiu", "svm_threshold": "fiu",
               "hs_threshold": "fiu", "variance_threshold": "fiu", "window_sizes": "iu", "window_margin": "fiu",
               "reference_width": "iu", "crown_ratios": "fiu", "seed": "iu", "notes": "U", "provenance": "U"}
SCALAR_FIELDS = ("format_version", "species", "svm_kind", "svm_bias", "edge_threshold", "colour_kind",
                 "window_margin", "reference_width", "seed", "notes", "provenance")
REQUIRED_KEYS = tuple(FIELD_KINDS)
COLOUR_LENGTH = 2 * colours.HS_BINS
LFS_POINTER_PREFIX = b"version https://git-lfs"
NPZ_MAGIC = b"PK\x03\x04"
NPY_MAGIC = b"\x93NUMPY"
SECOND_STAGE_KINDS = {"second_window": "iu", "second_weights": "fiu", "second_bias": "fiu", "second_threshold": "fiu"}
CNN_KINDS = {"cnn_onnx": "u", "cnn_side": "iu", "cnn_threshold": "fiu"}
CNN_SIDES = (16, 128)  # smallest and largest input side a model may ask for
# What a model's windows may be, from the frames the camera can deliver: the frame width its window sizes refer
# to (JeVois-A33 modes are 88..1280 px wide), and the windows no larger than the shorter side of such a frame
# (the narrowest sensor mode is 4:3: every frame is at least 3/4 as high as it is wide). A window/crown ratio
# window_margin above MAX_WINDOW_RATIO is no training window (`train --margin` stops there); a crown ratio above
# MAX_CROWN_RATIO gives, for the smallest crown the detector takes (8 px), a window beyond the largest frame
# side (1024 px): it never fits.
REFERENCE_WIDTHS = (64, 2048)
FRAME_HEIGHT_PER_WIDTH = 0.75
MAX_WINDOW_RATIO = 4.0
MAX_CROWN_RATIO = 1024 / 8.0


class ModelFormatError(ValueError):
    """The file is not a ForaNav model this code can use (message names the file and the problem)."""


def current_hog_config():
    return np.array([features.HOG_WINDOW, features.HOG_CELL, features.HOG_BLOCK, features.HOG_BLOCK_STRIDE,
                     features.HOG_BINS, features.ANGLE_LEVELS, int(round(features.BLOCK_NORM_EPS * _EPS_SCALE))],
                    np.int32)


class Domain(object):
    """One imagery's colour model and thresholds (see the module comment)."""

    def __init__(self, name, svm_threshold, hs_threshold, variance_threshold, colour_vectors, colour_bias=0.0,
                 frame_colour=None, second_threshold=0.0, cnn_threshold=0.0):
        self.name = str(name)
        self.second_threshold = float(second_threshold)  # used only by a model with a second stage
        self.cnn_threshold = float(cnn_threshold)  # used only by a model with a network
        self.svm_threshold = float(svm_threshold)
        self.hs_threshold = float(hs_threshold)
        self.variance_threshold = float(variance_threshold)
        self.colour_vectors = np.asarray(colour_vectors, np.float32).reshape(-1, COLOUR_LENGTH)
        self.colour_bias = float(colour_bias)
        if frame_colour is None:  # no frames known: the crowns' colour stands for the frame's
            frame_colour = self.colour_vectors.mean(axis=0)
        self.frame_colour = np.asarray(frame_colour, np.float32).ravel()

    def validate(self):
        if not self.name or len(self.name.split()) != 1:
            raise ModelFormatError("domain name %r must be one word" % self.name)
        if self.frame_colour.shape != (COLOUR_LENGTH,) or len(self.colour_vectors) == 0:
            raise ModelFormatError("domain %s: colour vectors must have %d values" % (self.name, COLOUR_LENGTH))
        values = [self.svm_threshold, self.hs_threshold, self.variance_threshold, self.colour_bias,
                  self.second_threshold, self.cnn_threshold]
        if not (np.all(np.isfinite(values)) and np.all(np.isfinite(self.colour_vectors))
                and np.all(np.isfinite(self.frame_colour))):
            raise ModelFormatError("domain %s: numbers must be finite" % self.name)


class TreeModel(object):
    """A trained detector model (see the module comment for the meaning of each field).

    Built with one colour template (template_hue, template_sat) and one set of thresholds, it holds one
    domain named `domain_name`; `domains` replaces them by several. svm_threshold, hs_threshold,
    variance_threshold, template_hue and template_sat read (and set) the first domain's.
    """

    def __init__(self, species, svm_weights, svm_bias, svm_threshold=0.0, variance_threshold=0.0,
                 hs_threshold=-1.0, template_hue=None, template_sat=None, window_sizes=(96,), window_margin=1.3,
                 reference_width=352, seed=0, notes="", edge_threshold=DEFAULT_EDGE_THRESHOLD, domains=None,
                 colour_kind="templates", crown_ratios=None, provenance="", domain_name="default",
                 second_window=None, second_weights=None, second_bias=0.0, second_kind="hog",
                 second_views=1, cnn_onnx=None, cnn_side=None):
        self.species = str(species)
        self.svm_weights = np.asarray(svm_weights, np.float32).ravel()
        self.svm_bias = float(svm_bias)
        self.edge_threshold = float(edge_threshold)
        self.colour_kind = str(colour_kind)
        if domains is None:
            hue = np.ones(colours.HS_BINS) if template_hue is None else template_hue
            sat = np.ones(colours.HS_BINS) if template_sat is None else template_sat
            hue, sat = np.asarray(hue, np.float32).ravel(), np.asarray(sat, np.float32).ravel()
            if hue.shape != (colours.HS_BINS,) or sat.shape != (colours.HS_BINS,):
                raise ModelFormatError("template_hue and template_sat must have %d bins" % colours.HS_BINS)
            domains = [Domain(domain_name, svm_threshold, hs_threshold, variance_threshold,
                              np.concatenate([hue, sat])[None, :])]
        self.domains = list(domains)
        self.window_sizes = tuple(int(w) for w in np.asarray(window_sizes).ravel())
        self.window_margin = float(window_margin)
        self.reference_width = int(reference_width)
        if crown_ratios is None:  # the training windows' own ratio
            crown_ratios = (self.window_margin,)
        self.crown_ratios = tuple(float(r) for r in np.asarray(crown_ratios).ravel())
        self.seed = int(seed)
        self.notes = str(notes)
        self.provenance = str(provenance)
        self.second_window = None if second_window is None else int(second_window)
        self.second_weights = None if second_weights is None else np.asarray(second_weights, np.float32).ravel()
        self.second_bias = float(second_bias)
        self.second_kind = str(second_kind)
        self.second_views = int(second_views)
        self.cnn_onnx = None if cnn_onnx is None else bytes(bytearray(np.asarray(cnn_onnx, np.uint8).ravel()))
        self.cnn_side = None if cnn_side is None else int(cnn_side)
        self.validate()

    # The first domain's values (single-imagery models, the camera's settings, older callers).
    svm_threshold = property(lambda self: self.domains[0].svm_threshold,
                             lambda self, value: setattr(self.domains[0], "svm_threshold", float(value)))
    hs_threshold = property(lambda self: self.domains[0].hs_threshold,
                            lambda self, value: setattr(self.domains[0], "hs_threshold", float(value)))
    variance_threshold = property(lambda self: self.domains[0].variance_threshold,
                                  lambda self, value: setattr(self.domains[0], "variance_threshold", float(value)))
    template_hue = property(lambda self: self.domains[0].colour_vectors[0, :colours.HS_BINS])
    template_sat = property(lambda self: self.domains[0].colour_vectors[0, colours.HS_BINS:])

    def domain(self, name):
        """The domain of this name; ModelFormatError (naming the known ones) when there is none."""
        for domain in self.domains:
            if domain.name == name:
                return domain
        raise ModelFormatError("no domain %r in the model (it has %s)"
                               % (name, ", ".join(d.name for d in self.domains)))

    def validate(self):
        length = features.hog_descriptor_length()
        if self.svm_weights.shape != (length,):
            raise ModelFormatError("svm_weights has %d values, the HOG descriptor has %d"
                                   % (self.svm_weights.size, length))
        if not self.window_sizes or min(self.window_sizes) < features.HOG_WINDOW:
            raise ModelFormatError("window_sizes must be non-empty and at least %d px" % features.HOG_WINDOW)
        if not REFERENCE_WIDTHS[0] <= self.reference_width <= REFERENCE_WIDTHS[1]:
            raise ModelFormatError("reference_width %d px is no camera frame width (%d..%d px)"
                                   % ((self.reference_width,) + REFERENCE_WIDTHS))
        if max(self.window_sizes) > largest_window(self.reference_width):
            raise ModelFormatError("window_sizes up to %d px do not fit the camera's frames (at most %d px, the "
                                   "shorter side of a frame %d px wide)" % (max(self.window_sizes),
                                                                           largest_window(self.reference_width),
                                                                           self.reference_width))
        if not self.species or len(self.species.split()) != 1:
            raise ModelFormatError("species must be one word")
        if self.colour_kind not in colours.COLOUR_KINDS:
            raise ModelFormatError("colour_kind %r is not one of %s" % (self.colour_kind,
                                                                      ", ".join(colours.COLOUR_KINDS)))
        if not self.domains:
            raise ModelFormatError("a model needs at least one domain")
        names = [d.name for d in self.domains]
        if len(set(names)) != len(names):
            raise ModelFormatError("domain names must be unique")
        for domain in self.domains:
            domain.validate()
        counts = set(len(d.colour_vectors) for d in self.domains)
        if len(counts) != 1 or (self.colour_kind == "linear" and counts != {1}):
            raise ModelFormatError("every domain needs the same number of colour vectors (linear: 1)")
        if (self.second_window is None) != (self.second_weights is None):
            raise ModelFormatError("a second stage needs its window and its weights")
        if self.second_window is not None:
            if self.second_window % features.HOG_CELL or self.second_window < features.HOG_BLOCK * features.HOG_CELL:
                raise ModelFormatError("second_window must be a multiple of %d px" % features.HOG_CELL)
            if self.second_kind not in features.SECOND_STAGE_KINDS:
                raise ModelFormatError("second_kind %r is not one of %s" % (self.second_kind,
                                                                          ", ".join(features.SECOND_STAGE_KINDS)))
            if self.second_views not in features.SECOND_STAGE_VIEWS:
                raise ModelFormatError("second_views %r is not one of %s" % (self.second_views,
                                                                             features.SECOND_STAGE_VIEWS))
            length = features.second_stage_length(self.second_window, self.second_kind)
            if self.second_weights.shape != (length,):
                raise ModelFormatError("second_weights has %d values, its descriptor has %d"
                                       % (self.second_weights.size, length))
            if not np.all(np.isfinite(self.second_weights)) or not np.isfinite(self.second_bias):
                raise ModelFormatError("second-stage numbers must be finite")
        if (self.cnn_onnx is None) != (self.cnn_side is None):
            raise ModelFormatError("a network needs its ONNX bytes and its input side")
        if self.cnn_onnx is not None and (not self.cnn_onnx or not CNN_SIDES[0] <= self.cnn_side <= CNN_SIDES[1]):
            raise ModelFormatError("cnn_onnx must not be empty and cnn_side must be %d..%d px" % CNN_SIDES)
        values = [self.svm_bias, self.edge_threshold, self.window_margin] + list(self.svm_weights)
        values += list(self.crown_ratios)
        if not np.all(np.isfinite(values)) or not self.crown_ratios:
            raise ModelFormatError("model numbers must be finite")
        if not 0 < self.window_margin <= MAX_WINDOW_RATIO:
            raise ModelFormatError("window_margin must be in (0, %g], got %g" % (MAX_WINDOW_RATIO, self.window_margin))
        if not (min(self.crown_ratios) > 0 and max(self.crown_ratios) <= MAX_CROWN_RATIO):
            raise ModelFormatError("crown_ratios must be in (0, %g], got %s"
                                   % (MAX_CROWN_RATIO, ", ".join("%g" % r for r in self.crown_ratios)))

    def score(self, descriptor):
        """SVM decision value of one top-layer descriptor (positive = tree-like)."""
        return float(np.dot(self.svm_weights, descriptor)) + self.svm_bias

    def second_score(self, value_window):
        """The second stage's decision value of one full-resolution value window."""
        descriptor = features.second_stage_descriptor(value_window, self.second_window, self.second_kind,
                                                      self.second_views)
        return float(np.dot(self.second_weights, descriptor)) + self.second_bias

    def to_arrays(self):
        arrays = self._core_arrays()
        if self.second_window is not None:  # only then: a model without one keeps its bytes
            arrays.update(second_window=np.array(self.second_window, np.int32), second_weights=self.second_weights,
                          second_bias=np.array(self.second_bias, np.float32),
                          second_threshold=np.array([d.second_threshold for d in self.domains], np.float32))
            if self.second_kind != "hog":
                arrays.update(second_kind=np.array(self.second_kind))
            if self.second_views != 1:
                arrays.update(second_views=np.array(self.second_views, np.int32))
        if self.cnn_onnx is not None:  # only then: a model without one keeps its bytes
            arrays.update(cnn_onnx=np.frombuffer(self.cnn_onnx, np.uint8), cnn_side=np.array(self.cnn_side, np.int32),
                          cnn_threshold=np.array([d.cnn_threshold for d in self.domains], np.float32))
        return arrays

    def _core_arrays(self):
        domains = self.domains
        return {
            "format_version": np.array(FORMAT_VERSION, np.int32),
            "species": np.array(self.species),  # fixed-width unicode, no pickle
            "hog_config": current_hog_config(),
            "svm_kind": np.array("linear"),
            "svm_weights": self.svm_weights,
            "svm_bias": np.array(self.svm_bias, np.float32),
            "edge_threshold": np.array(self.edge_threshold, np.float32),
            "colour_kind": np.array(self.colour_kind),
            "domain_names": np.array([d.name for d in domains]),
            "colour_vectors": np.array([d.colour_vectors for d in domains], np.float32),
            "colour_bias": np.array([d.colour_bias for d in domains], np.float32),
            "frame_colour": np.array([d.frame_colour for d in domains], np.float32),
            "svm_threshold": np.array([d.svm_threshold for d in domains], np.float32),
            "hs_threshold": np.array([d.hs_threshold for d in domains], np.float32),
            "variance_threshold": np.array([d.variance_threshold for d in domains], np.float32),
            "window_sizes": np.array(self.window_sizes, np.int32),
            "window_margin": np.array(self.window_margin, np.float32),
            "reference_width": np.array(self.reference_width, np.int32),
            "crown_ratios": np.array(self.crown_ratios, np.float32),
            "seed": np.array(self.seed, np.int64),
            "notes": np.array(self.notes),
            "provenance": np.array(self.provenance),
        }


def largest_window(reference_width):
    """The largest window side (px) that fits every frame `reference_width` px wide (its shorter side)."""
    return int(reference_width * FRAME_HEIGHT_PER_WIDTH)


def check_network(model, name="model"):
    """The model's network (if any) loads in OpenCV and gives a logit for one window; ModelFormatError otherwise.

    Without this a network OpenCV cannot read fails on the first frame the camera processes (on the camera:
    every frame, so the flight sees no tree at all)."""
    if model.cnn_onnx is None:
        return
    import foranav_cnn  # only models with a network need OpenCV's dnn module
    problem = foranav_cnn.network_problem(model.cnn_onnx, model.cnn_side)
    if problem:
        raise ModelFormatError("%s: field cnn_onnx: the network does not run in OpenCV (%s)" % (name, problem))


def save_model(model, file_obj):
    """Write the model as an uncompressed .npz to a path or binary file object (use an atomic writer)."""
    np.savez(file_obj, **model.to_arrays())


def _head(path, count=64):
    """The first bytes of a path or seekable binary file object (the file object is rewound)."""
    if hasattr(path, "read"):
        start = path.tell()
        head = path.read(count)
        path.seek(start)
        return head
    with open(path, "rb") as handle:
        return handle.read(count)


def load_model(path, name=None):
    """Read a model file; raises ModelFormatError (one line naming the file) for anything unusable.

    numpy's own messages are never passed on for files that are not .npz archives: for text they suggest
    unpickling, which must never be done with a file of unknown origin. `name` names a file object in messages."""
    label = path if name is None else name
    try:
        head = _head(path)
    except (IOError, OSError) as err:
        raise ModelFormatError("%s: cannot read the model file (%s)" % (label, getattr(err, "strerror", None) or err))
    if not head:
        raise ModelFormatError("%s: the model file is empty" % label)
    if head.startswith(LFS_POINTER_PREFIX):
        raise ModelFormatError("%s: a Git LFS pointer, not the model itself (fetch it with 'git lfs pull')" % label)
    if head.startswith(NPY_MAGIC):
        raise ModelFormatError("%s: a single .npy array, not a ForaNav model (.npz archive)" % label)
    if not head.startswith(NPZ_MAGIC):
        raise ModelFormatError("%s: not a ForaNav model (not an .npz archive)" % label)
    _check_archive(path, label)
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {key: data[key] for key in data.files}
    except (IOError, OSError, ValueError, EOFError, KeyError, zipfile.BadZipfile, RuntimeError) as err:
        problem = str(err).splitlines()[0] if str(err) else type(err).__name__
        if "pickle" in problem.lower():
            problem = "it holds Python objects, which a model never does"
        raise ModelFormatError("%s: damaged or not a model file (%s)" % (label, problem))
    model = model_from_arrays(arrays, label)
    check_network(model, label)
    return model


def _check_archive(path, label):
    """A readable zip archive whose members all pass their CRC check (before numpy sees it: numpy 1.16 prints
    a stray traceback for a truncated archive)."""
    start = path.tell() if hasattr(path, "read") else None
    try:
        with zipfile.ZipFile(path) as archive:
            damaged = archive.testzip()
    except (zipfile.BadZipfile, IOError, OSError, EOFError, ValueError, RuntimeError) as err:
        raise ModelFormatError("%s: damaged or truncated model file (%s)" % (label, str(err).splitlines()[0] if str(err)
                                                                            else type(err).__name__))
    finally:
        if start is not None:
            path.seek(start)
    if damaged is not None:
        raise ModelFormatError("%s: damaged model file (%s fails its CRC check)" % (label, damaged))


def _check_field_types(arrays, name):
    for key, kinds in FIELD_KINDS.items():
        array = arrays[key]
        if not isinstance(array, np.ndarray) or array.dtype.kind not in kinds:
            raise ModelFormatError("%s: field %s has the wrong type (%s)" % (name, key, getattr(array, "dtype", "?")))
        if key in SCALAR_FIELDS and array.size != 1:
            raise ModelFormatError("%s: field %s must be a single value" % (name, key))


def model_from_arrays(arrays, name="model"):
    if "format_version" not in arrays:
        raise ModelFormatError("%s: not a ForaNav model (no format_version)" % name)
    try:
        version = int(arrays["format_version"])
    except (TypeError, ValueError):
        raise ModelFormatError("%s: field format_version has the wrong type" % name)
    if version != FORMAT_VERSION:
        raise ModelFormatError("%s: model format version %d, this detector reads version %d (retrain it with "
                               "'foranav train')" % (name, version, FORMAT_VERSION))
    missing = [key for key in REQUIRED_KEYS if key not in arrays]
    if missing:
        raise ModelFormatError("%s: missing %s" % (name, ", ".join(missing)))
    _check_field_types(arrays, name)
    if not np.array_equal(np.asarray(arrays["hog_config"]), current_hog_config()):
        raise ModelFormatError("%s: trained with HOG configuration %s, this detector uses %s"
                               % (name, list(arrays["hog_config"]), list(current_hog_config())))
    kind = str(arrays["svm_kind"])
    if kind not in SVM_KINDS:
        raise ModelFormatError("%s: SVM kind %r is not supported (only %s)" % (name, kind, ", ".join(SVM_KINDS)))
    try:
        names = [str(n) for n in np.asarray(arrays["domain_names"]).ravel()]
        count = len(names)
        vectors = np.asarray(arrays["colour_vectors"], np.float32)
        if vectors.ndim != 3 or vectors.shape[0] != count or vectors.shape[2] != COLOUR_LENGTH:
            raise ModelFormatError("colour_vectors must be (%d domains, K, %d)" % (count, COLOUR_LENGTH))
        per_domain = {}
        for key in ("colour_bias", "svm_threshold", "hs_threshold", "variance_threshold"):
            per_domain[key] = np.asarray(arrays[key], np.float64).ravel()
            if per_domain[key].shape != (count,):
                raise ModelFormatError("%s must have one value per domain (%d)" % (key, count))
        frame_colour = np.asarray(arrays["frame_colour"], np.float32)
        if frame_colour.shape != (count, COLOUR_LENGTH):
            raise ModelFormatError("frame_colour must be (%d domains, %d)" % (count, COLOUR_LENGTH))
        second = _second_stage(arrays, count)
        cnn = _cnn_stage(arrays, count)
        domains = [Domain(names[i], per_domain["svm_threshold"][i], per_domain["hs_threshold"][i],
                          per_domain["variance_threshold"][i], vectors[i], per_domain["colour_bias"][i],
                          frame_colour[i], second["threshold"][i], cnn["threshold"][i]) for i in range(count)]
        return TreeModel(
            species=str(arrays["species"]), svm_weights=arrays["svm_weights"], svm_bias=float(arrays["svm_bias"]),
            edge_threshold=float(arrays["edge_threshold"]), colour_kind=str(arrays["colour_kind"]),
            domains=domains, window_sizes=arrays["window_sizes"], window_margin=float(arrays["window_margin"]),
            reference_width=int(arrays["reference_width"]), crown_ratios=arrays["crown_ratios"],
            seed=int(arrays["seed"]), notes=str(arrays["notes"]), provenance=str(arrays["provenance"]),
            second_window=second["window"], second_weights=second["weights"], second_bias=second["bias"],
            second_kind=second["kind"], second_views=second["views"], cnn_onnx=cnn["onnx"], cnn_side=cnn["side"])
    except ModelFormatError as err:
        raise ModelFormatError("%s: %s" % (name, err))
    except (TypeError, ValueError, IndexError) as err:
        raise ModelFormatError("%s: a field has the wrong type or shape (%s)" % (name, err))


def _optional_stage(arrays, kinds, what, threshold_key, count):
    """The fields of an optional stage, checked: all of `kinds` or none (None); its per-domain thresholds."""
    present = [key for key in kinds if key in arrays]
    if not present:
        return None
    if len(present) != len(kinds):
        raise ModelFormatError("%s incomplete (missing %s)" % (what, ", ".join(k for k in kinds if k not in arrays)))
    for key, allowed in kinds.items():
        if arrays[key].dtype.kind not in allowed or (allowed == "u" and arrays[key].dtype.itemsize != 1):
            raise ModelFormatError("field %s has the wrong type (%s)" % (key, arrays[key].dtype))
    threshold = np.asarray(arrays[threshold_key], np.float64).ravel()
    if threshold.shape != (count,):
        raise ModelFormatError("%s must have one value per domain (%d)" % (threshold_key, count))
    return list(threshold)


def _second_stage(arrays, count):
    """The optional second stage's fields: all four keys or none (window None: no second stage)."""
    threshold = _optional_stage(arrays, SECOND_STAGE_KINDS, "second stage", "second_threshold", count)
    if threshold is None:
        return {"window": None, "weights": None, "bias": 0.0, "threshold": [0.0] * count, "kind": "hog",
                "views": 1}
    kind = arrays.get("second_kind", np.array("hog"))
    if kind.dtype.kind != "U" or kind.size != 1:
        raise ModelFormatError("field second_kind has the wrong type (%s)" % kind.dtype)
    views = arrays.get("second_views", np.array(1))
    if views.dtype.kind not in "iu" or views.size != 1:
        raise ModelFormatError("field second_views has the wrong type (%s)" % views.dtype)
    return {"window": int(arrays["second_window"]), "weights": arrays["second_weights"],
            "bias": float(arrays["second_bias"]), "threshold": threshold, "kind": str(kind), "views": int(views)}


def _cnn_stage(arrays, count):
    """The optional network's fields: all three keys or none (onnx None: no network)."""
    threshold = _optional_stage(arrays, CNN_KINDS, "network", "cnn_threshold", count)
    if threshold is None:
        return {"onnx": None, "side": None, "threshold": [0.0] * count}
    if arrays["cnn_side"].size != 1:
        raise ModelFormatError("field cnn_side must be a single value")
    return {"onnx": arrays["cnn_onnx"], "side": int(arrays["cnn_side"]), "threshold": threshold}
