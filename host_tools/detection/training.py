"""Training a detector model from annotated imageries (pure: frames + seed in, TreeModel out).

An imagery is the frames of one training CSV (one camera, light and place). The model holds one shared SVM
and, per imagery with trees of the species (a "domain"), a colour model and the three thresholds.

1. Positives: every complete tree of the species, window = crown x margin, with size jitter (so one window
   size covers the gap to the next), a little centre jitter and the 8 rotations/mirrors (trees seen from
   above have no preferred orientation).
2. Negatives: boxes of other labels (look-alike palms, roofs, road crossings), windows shifted off a tree by
   35-60 % of W (incomplete trees, as the paper's negatives), windows of the wrong size on a tree, and
   random background windows (survey imagery: at its crown scale, inside the annotated area).
3. A linear SVM (host_tools.detection.svm), then hard-negative mining: the detector's own score maps on
   the training frames give the false alarms of the current model, which are added and the SVM retrained.
   Flight-camera frames (reference_width wide) are mined with the model's window sizes; survey imagery at
   its own crown sizes and only inside each frame's annotated area (sites that annotate one block).
4. Per domain: the colour model (the mean hue and saturation histograms of its crowns, K templates, or a
   linear classifier), and the SVM, colour and variance thresholds chosen together on crop-protocol windows
   of its frames held back from the SVM (best balanced accuracy with recall >= MIN_RECALL).
5. Whole frames: the edge test on held-back camera frames; the window/crown ratios (detection at a given
   crown size) on held-back survey frames (best frame F1).

Steps 1-3's examples live in ``detection.examples``, steps 4-5 in ``detection.calibration``; this module
composes them (``train``) and re-exports their names.
"""
import io
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from host_tools.detection import cnn as cnn_stage
from host_tools.detection import dataset
from host_tools.detection.calibration import (  # noqa: F401  (training's names before the split)
    CALIBRATION_CROPS, CROWN_RATIO_CENTRES, CROWN_RATIO_SPREAD, CUE_QUANTILES, EDGE_THRESHOLDS, MIN_RECALL,
    SVM_THRESHOLDS, below_quantile as _below_quantile, calibrate as _calibrate, calibrate_edge as _calibrate_edge,
    calibrate_frames as _calibrate_frames, texture_cap)
from host_tools.detection.examples import Representatives
from host_tools.detection.examples import (  # noqa: F401
    BACKGROUND_PER_FRAME, CENTRE_JITTER, COLOUR_SVM_C, HARD_NEGATIVE_SCORE, HARD_NEGATIVES_PER_FRAME,
    LOOKALIKE_COPIES, POSITIVE_COPIES, SHIFTED_PER_TREE, SIZE_JITTER, SURVEY_BACKGROUND_SCALE,
    colour_model as _colour_model, crop_descriptors as _crop_descriptors, hard_negatives as _hard_negatives,
    negative_descriptors as _negative_descriptors, negative_windows as _negative_windows,
    positive_descriptors as _positive_descriptors, second_stage_examples as _second_stage_examples, survey_windows)
from host_tools.detection.progress import Progress
from host_tools.detection.svm import train_linear_svm

import foranav_colour as colours

import foranav_features as features
from foranav_model import Domain, TreeModel

DEFAULT_WINDOW_SIZES = (96, 120, 144, 168)  # at 352 px frame width, margin 1.3: crowns of about 60-155 px
DEFAULT_REFERENCE_WIDTH = 352
SECOND_STAGE_WINDOW = features.SECOND_STAGE_WINDOWS[0]
SECOND_STAGE_C = 1.0
DEFAULT_SECOND_KIND = "hog+radial"  # docs/detector.md: the radial cue lifts the crop protocol and frame F1
DEFAULT_SECOND_VIEWS = 4  # docs/detector.md: the mean over the quarter turns won on both training-side splits
DEFAULT_MARGIN = 1.3  # window side / crown diameter: the crown plus a ring of ground (its outline)
HARD_NEGATIVE_ROUNDS = 3
SVM_C = 1.0
CALIBRATION_SPLIT = 0.2  # fraction of the frames held back to choose the thresholds ...
CALIBRATION_CROWNS = 500  # ... but no more survey frames than hold this many crowns (a photo holds 100-200)


@dataclass
class Imagery:
    """One imagery (a training CSV): its frames share a camera, light and place, so one colour model."""
    name: str
    frames: list
    source: str = ""


def as_imageries(data: Sequence[Imagery] | Sequence[dataset.Frame]) -> list[Imagery]:
    """A list of Imagery, or of frames (one imagery named 'default')."""
    data = list(data)
    if data and not isinstance(data[0], Imagery):
        return [Imagery("default", data)]
    return data


def is_camera_imagery(imagery: Imagery, reference_width: int) -> bool:
    """Frames of the flight camera (the model's reference width): the model's window sizes fit them."""
    return all(f.width == reference_width for f in imagery.frames)


def calibration_count(n_frames: int) -> int:
    """Frames held back per imagery: a fifth; one of a small imagery (3-9 frames); none below 3."""
    if n_frames >= 10:
        return int(round(CALIBRATION_SPLIT * n_frames))
    return 1 if n_frames >= 3 else 0


def train(data: Sequence[Imagery] | Sequence[dataset.Frame], species: str, seed: int = 0,
          window_sizes: Sequence[int] = DEFAULT_WINDOW_SIZES, reference_width: int = DEFAULT_REFERENCE_WIDTH,
          margin: float = DEFAULT_MARGIN, log: Callable[[str], None] | None = None, crops: Sequence = (),
          colour_kind: str = "templates", colour_templates: int = 1, provenance: str = "",
          second_kind: str = DEFAULT_SECOND_KIND, second_views: int = DEFAULT_SECOND_VIEWS,
          cnn: bool = False, progress: Progress | None = None) -> TreeModel:
    """Train a TreeModel for `species` from annotated imageries (or frames). Same inputs and seed -> same model.

    Each imagery's frames are split (seeded): the SVM learns from CALIBRATION_SPLIT's complement, and the
    imagery's thresholds are chosen on its held-back frames' crop-protocol windows, so that they see honest
    SVM scores. An imagery without trees of the species only adds negatives. crops: [(bgr, is positive)]
    ready-made windows added to the SVM's examples. Frames of the flight camera (reference_width wide) are
    mined with the model's window sizes; survey imagery at its own crown sizes, inside each frame's
    annotated area. cnn: also train the learned stage (host_tools.detection.cnn; needs PyTorch). progress:
    told each phase's steps (frames) as they are done.
    """
    log = log or (lambda message: None)
    imageries = as_imageries(data)
    if colour_kind not in colours.COLOUR_KINDS:
        raise ValueError("colour model must be one of %s" % ", ".join(colours.COLOUR_KINDS))
    rng = np.random.RandomState(seed)
    learning, calibration = {}, {}
    for imagery in imageries:
        order = rng.permutation(len(imagery.frames))
        n_calibration = calibration_count(len(imagery.frames))
        if not is_camera_imagery(imagery, reference_width):
            crowns = np.cumsum([len(imagery.frames[i].trees(species)) for i in order[:n_calibration]])
            n_calibration = min(n_calibration, 1 + int(np.searchsorted(crowns, CALIBRATION_CROWNS)))
        calibration[imagery.name] = [imagery.frames[i] for i in sorted(order[:n_calibration])]
        learning[imagery.name] = [imagery.frames[i] for i in sorted(order[n_calibration:])]
    camera = {im.name: is_camera_imagery(im, reference_width) for im in imageries}
    progress = progress or Progress(io.StringIO())
    progress.plan(_phases(imageries, learning, calibration, camera, cnn))

    def each(phase, imagery):  # the imagery's learning frames one by one (the same random draws as all at once)
        for frame in learning[imagery.name]:
            yield [frame]
            progress.tick(phase)
    positives = np.vstack([_positive_descriptors(frames, species, margin, rng) for im in imageries
                           for frames in each("positives", im)])
    if len(positives) == 0:
        raise ValueError("no complete '%s' trees in the training data" % species)
    negatives = np.vstack([_negative_descriptors(frames, species, margin, rng, not camera[im.name])
                           for im in imageries for frames in each("negatives", im)])
    if crops:  # ready-made windows (image, is positive): each image is one window
        crop_positives, crop_negatives = _crop_descriptors(crops, rng)
        positives = np.vstack([positives, crop_positives])
        negatives = np.vstack([negatives, crop_negatives])
    if len(negatives) == 0:
        raise ValueError("no negative windows in the training data")
    log("%d frames to learn from, %d to calibrate on; positives %d, negatives %d"
        % (sum(len(f) for f in learning.values()), sum(len(f) for f in calibration.values()), len(positives),
           len(negatives)))
    targets = [im for im in imageries if any(f.trees(species) for f in learning[im.name])]
    domains = []
    for imagery in targets:
        vectors, bias = _colour_model(learning[imagery.name], species, margin, colour_kind, colour_templates, rng,
                                      not camera[imagery.name])
        frame_colour = np.mean([colours.frame_colour(f.hsv) for f in imagery.frames], axis=0)
        domains.append(Domain(imagery.name, 0.0, -1.0, 0.0, vectors, bias, frame_colour))
    model = TreeModel(
        species=species, svm_weights=np.zeros(features.hog_descriptor_length()), svm_bias=0.0, domains=domains,
        colour_kind=colour_kind, window_sizes=window_sizes, window_margin=margin, reference_width=reference_width,
        seed=seed, provenance=provenance)
    for round_index in range(HARD_NEGATIVE_ROUNDS + 1):
        x = np.vstack([positives, negatives])
        y = np.concatenate([np.ones(len(positives)), -np.ones(len(negatives))])
        model.svm_weights, model.svm_bias = train_linear_svm(x, y, c=SVM_C, seed=seed + round_index)
        if round_index == HARD_NEGATIVE_ROUNDS:
            break
        hard = np.vstack([_hard_negatives(frames, species, model, rng, not camera[im.name])
                          for im in imageries for frames in each("mining round %d" % (round_index + 1), im)])
        log("round %d: %d hard negatives" % (round_index + 1, len(hard)))
        if len(hard) == 0:
            break
        negatives = np.vstack([negatives, hard])
    representatives = Representatives(model)  # the first stage's, shared by the later stages' examples
    if any(not camera[im.name] for im in targets):  # survey imagery: camera (rendered) models stay one stage
        _train_second_stage(model, imageries, learning, camera, species, seed, log, second_kind, second_views, each,
                            representatives)
    if cnn:
        _train_cnn(model, imageries, learning, camera, species, seed, log, each, progress, representatives)
    for index, imagery in enumerate(targets):
        cap = None if camera[imagery.name] else texture_cap(imagery.frames, species, margin)
        _calibrate(model, index, calibration[imagery.name] or learning[imagery.name], rng, log, cap)
        progress.tick("thresholds")
    camera_targets = [im for im in targets if camera[im.name]]
    survey_targets = [im for im in targets if not camera[im.name]]
    if camera_targets:  # frames of one camera: the model's window sizes fit them
        _calibrate_edge(model, [(im.name, calibration[im.name] or learning[im.name]) for im in camera_targets], log)
    else:  # survey imagery: a crown cut by the edge is still annotated; keep the default
        log("edge test: survey imagery, default threshold %.2f kept" % model.edge_threshold)
    if survey_targets:
        _calibrate_frames(model, [(im.name, calibration[im.name] or learning[im.name]) for im in survey_targets],
                          log, lambda: progress.tick("whole frames"))
    else:
        crowns = [dataset.crown_size(b) for im in camera_targets for f in im.frames for b in f.trees(species)]
        model.crown_ratios = tuple(round(w / float(np.median(crowns)), 4) for w in window_sizes)
    model.notes = ("species %s; %d frames (%d calibration) of %d imageries (%s); %d positives, %d negatives; seed %d"
                   % (species, sum(len(im.frames) for im in imageries), sum(len(f) for f in calibration.values()),
                      len(imageries), ", ".join(im.name for im in imageries), len(positives), len(negatives), seed))
    model.validate()
    return model


def _phases(imageries, learning, calibration, camera, cnn):
    """Training's phases for the progress bar: (name, steps, rough cost of a step relative to one learning
    frame's positives). A step is a frame, an epoch or an imagery."""
    n_learning = sum(len(f) for f in learning.values())
    n_survey = sum(len(calibration[im.name] or learning[im.name]) for im in imageries if not camera[im.name])
    phases = [("positives", n_learning, 1.0), ("negatives", n_learning, 1.0)]
    phases += [("mining round %d" % (r + 1), n_learning, 1.5) for r in range(HARD_NEGATIVE_ROUNDS)]
    if any(not camera[im.name] for im in imageries):
        phases.append(("second stage", n_learning, 3.0))
    if cnn:
        phases += [("network examples", n_learning, 3.0), ("network", cnn_stage.EPOCHS, n_learning / 10.0)]
    phases += [("thresholds", len(imageries), 10.0), ("whole frames", len(CROWN_RATIO_CENTRES) * n_survey, 1.0)]
    return phases


def _train_second_stage(model, imageries, learning, camera, species, seed, log, kind, views, each, representatives):
    """The second stage: a linear SVM on the `kind` descriptor at SECOND_STAGE_WINDOW px (HOG, radial cue) of
    the learning frames' windows, with the first stage's false alarms on survey frames as negatives (own
    random stream: the first stage's examples do not change). It learns from single windows, each in a
    random turn or mirror; `views` only sets how a window is scored (model.second_views)."""
    rng = np.random.RandomState(seed + 1)
    parts = [_second_stage_examples(frames, species, model, SECOND_STAGE_WINDOW, kind, rng, not camera[im.name],
                                    representatives) for im in imageries for frames in each("second stage", im)]
    x = np.vstack([part[0] for part in parts])
    y = np.concatenate([part[1] for part in parts])
    model.second_window, model.second_kind, model.second_views = SECOND_STAGE_WINDOW, kind, views
    model.second_weights, model.second_bias = train_linear_svm(x, y, c=SECOND_STAGE_C, seed=seed)
    log("second stage: %d px %s, %d view(s), %d positives, %d negatives"
        % (SECOND_STAGE_WINDOW, kind, views, (y > 0).sum(), (y < 0).sum()))


def _train_cnn(model, imageries, learning, camera, species, seed, log, each, progress, representatives):
    """The learned stage: the network on windows of every imagery's learning frames (own random stream)."""
    rng = np.random.RandomState(seed + 2)
    parts = [cnn_stage.frame_examples(frames, species, model, rng, not camera[im.name], representatives)
             for im in imageries for frames in each("network examples", im)]
    inputs = np.concatenate([part[0] for part in parts])
    labels = np.concatenate([part[1] for part in parts])
    log("network: %d crown windows, %d others" % (int(labels.sum()), int((labels == 0).sum())))
    model.cnn_onnx = cnn_stage.train_network(inputs, labels, seed, log, lambda: progress.tick("network"))
    model.cnn_side = inputs.shape[-1]
