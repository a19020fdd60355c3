"""Helpers shared by the detector commands: model lookup and loading with one-line errors."""
import argparse
import math
import os

import host_tools.detection  # noqa: F401  (puts the camera module folder on sys.path)
from host_tools.annotations import MAX_BOX_PX
from host_tools.errors import ForaNavError
from host_tools.jevois_host import DEFAULT_MODULE_DIR

import foranav_features
import foranav_model

SPECIES_MODELS = {"oil_palm": "foranav_oil_palm.npz", "citrus": "foranav_citrus.npz", "olive": "foranav_olive.npz"}


def model_path(name: str) -> str:
    """A species name (oil_palm, citrus, olive) -> the shipped model; anything else is a file path."""
    if name in SPECIES_MODELS:
        return os.path.join(DEFAULT_MODULE_DIR, SPECIES_MODELS[name])
    return name


def load(name: str) -> foranav_model.TreeModel:
    path = model_path(name)
    if not os.path.isfile(path):
        raise ForaNavError("%s: no such model file" % path)
    try:
        return foranav_model.load_model(path)
    except foranav_model.ModelFormatError as err:
        raise ForaNavError(str(err))


STEP_RANGE = (1, foranav_features.HOG_WINDOW)  # window step, downscaled pixels (the detector's own range)
MAX_DETECTIONS_RANGE = (1, 100000)  # trees reported per image
MIN_CROWN_PX = 8  # a crown smaller than this in the image is no tree the windows can frame
MAX_CROWN_PX = MAX_BOX_PX  # nor one larger than any image the readers take


def crown_pixels(args: argparse.Namespace, boxes: bool = False) -> float | str | None:
    """The crown diameter in pixels from --crown-px (a number; 'boxes' too when `boxes`) or --gsd with
    --crown-m (crown metres / metres per pixel), within MIN_CROWN_PX .. MAX_CROWN_PX; None when none is given."""
    if (args.gsd is None) != (args.crown_m is None):
        raise ForaNavError("--gsd and --crown-m go together (crown pixels = crown metres / metres per pixel)")
    if args.crown_px is not None and args.gsd is not None:
        raise ForaNavError("give --crown-px or --gsd with --crown-m, not both")
    if args.gsd is not None:
        for name, value in (("--gsd", args.gsd), ("--crown-m", args.crown_m)):
            if not (math.isfinite(value) and value > 0):
                raise ForaNavError("%s must be a positive number" % name)
        crown_px, option = args.crown_m / args.gsd, "--gsd %g --crown-m %g" % (args.gsd, args.crown_m)
    elif args.crown_px is None or (boxes and args.crown_px == "boxes"):
        return args.crown_px
    else:
        try:
            crown_px, option = float(args.crown_px), "--crown-px %s" % args.crown_px
        except ValueError:
            raise ForaNavError("--crown-px must be a number of pixels%s, got %r"
                               % (" or 'boxes'" if boxes else "", args.crown_px))
    if not (math.isfinite(crown_px) and MIN_CROWN_PX <= crown_px <= MAX_CROWN_PX):
        raise ForaNavError("%s: a crown of %.3g px; it must be %d .. %d px" % (option, crown_px, MIN_CROWN_PX,
                                                                          MAX_CROWN_PX))
    return crown_px


def check_crown_fits(crown_px: float | str | None, sizes: list[tuple[int, int]], what: str) -> None:
    """A crown size given in pixels must fit at least one of the images (width, height) it is used on."""
    if crown_px is None or crown_px == "boxes" or not sizes:
        return
    largest = max(min(size) for size in sizes)
    if crown_px > largest:
        raise ForaNavError("--crown-px: a crown of %.3g px does not fit %s (the largest is %d px on its shorter "
                           "side)" % (crown_px, what, largest))
