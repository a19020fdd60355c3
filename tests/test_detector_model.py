"""The model file (jevois_module/ForaNavTrees/foranav_model.py): plain arrays, versioned, no pickle."""
import io

import numpy as np
import pytest

import host_tools.detection  # noqa: F401
import foranav_features as features
import foranav_model
from host_tools.detection import common


def make_model(**overrides):
    rng = np.random.RandomState(0)
    fields = dict(species="oil_palm", svm_weights=rng.randn(features.hog_descriptor_length()), svm_bias=-0.5,
                  svm_threshold=0.1, variance_threshold=0.002, hs_threshold=0.6, template_hue=rng.rand(256),
                  template_sat=rng.rand(256), window_sizes=(96, 120), window_margin=1.3, reference_width=352,
                  seed=7, notes="test model", edge_threshold=-0.5)
    fields.update(overrides)
    return foranav_model.TreeModel(**fields)


def saved(model_or_arrays):
    buffer = io.BytesIO()
    if isinstance(model_or_arrays, dict):
        np.savez(buffer, **model_or_arrays)
    else:
        foranav_model.save_model(model_or_arrays, buffer)
    buffer.seek(0)
    return buffer


def test_that_a_model_round_trips_through_its_file_without_pickle():
    model = make_model()
    loaded = foranav_model.load_model(saved(model))  # load_model uses allow_pickle=False
    assert loaded.species == "oil_palm" and loaded.notes == "test model" and loaded.seed == 7
    assert np.array_equal(loaded.svm_weights, model.svm_weights)
    assert np.array_equal(loaded.template_hue, model.template_hue)
    assert loaded.window_sizes == (96, 120)
    for name in ("svm_bias", "svm_threshold", "variance_threshold", "hs_threshold", "edge_threshold",
                 "window_margin"):
        assert getattr(loaded, name) == pytest.approx(getattr(model, name), rel=1e-6)


def test_that_strings_are_stored_as_fixed_width_unicode_arrays():
    arrays = make_model().to_arrays()
    assert arrays["species"].dtype.kind == "U" and arrays["svm_kind"].dtype.kind == "U"
    assert all(a.dtype != object for a in arrays.values())


def test_that_a_model_of_another_version_is_refused_with_a_clear_message():
    arrays = make_model().to_arrays()
    arrays["format_version"] = np.array(foranav_model.FORMAT_VERSION + 1)
    with pytest.raises(foranav_model.ModelFormatError, match="format version %d.*reads version %d"
                       % (foranav_model.FORMAT_VERSION + 1, foranav_model.FORMAT_VERSION)):
        foranav_model.load_model(saved(arrays))


def test_that_a_model_of_another_hog_configuration_is_refused():
    arrays = make_model().to_arrays()
    arrays["hog_config"] = arrays["hog_config"] + 1
    with pytest.raises(foranav_model.ModelFormatError, match="HOG configuration"):
        foranav_model.load_model(saved(arrays))


def test_that_missing_fields_and_non_models_are_refused():
    arrays = make_model().to_arrays()
    del arrays["template_sat"]
    with pytest.raises(foranav_model.ModelFormatError, match="missing template_sat"):
        foranav_model.load_model(saved(arrays))
    with pytest.raises(foranav_model.ModelFormatError, match="not a ForaNav model"):
        foranav_model.load_model(saved({"x": np.zeros(3)}))
    with pytest.raises(foranav_model.ModelFormatError, match="not a readable model"):
        foranav_model.load_model(io.BytesIO(b"not an npz"))


def test_that_inconsistent_models_are_refused():
    with pytest.raises(foranav_model.ModelFormatError, match="svm_weights"):
        make_model(svm_weights=np.zeros(10))
    with pytest.raises(foranav_model.ModelFormatError, match="window_sizes"):
        make_model(window_sizes=(12,))
    with pytest.raises(foranav_model.ModelFormatError, match="finite"):
        make_model(svm_bias=float("nan"))


@pytest.mark.parametrize("species", ["oil_palm", "citrus", "olive"])
def test_that_the_shipped_models_load_and_name_their_species(species):
    model = common.load(species)
    assert model.species == species
    assert len(model.window_sizes) >= 1 and model.reference_width == 352


@pytest.mark.parametrize("species", ["oil_palm", "citrus", "olive"])
def test_that_the_shipped_models_use_npy_format_1_0_which_numpy_1_16_reads(species):
    import zipfile
    with zipfile.ZipFile(common.model_path(species)) as archive:
        for name in archive.namelist():
            with archive.open(name) as member:
                assert np.lib.format.read_magic(member) == (1, 0), name
                assert member.read(1)  # a header follows; no pickled objects
