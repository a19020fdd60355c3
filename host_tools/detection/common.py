"""Helpers shared by the detector commands: model lookup and loading with one-line errors."""
import os

import host_tools.detection  # noqa: F401  (puts the camera module folder on sys.path)
from host_tools.errors import ForaNavError
from host_tools.jevois_host import DEFAULT_MODULE_DIR

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
