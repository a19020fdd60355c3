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
    del arrays["colour_vectors"]
    with pytest.raises(foranav_model.ModelFormatError, match="missing colour_vectors"):
        foranav_model.load_model(saved(arrays))
    with pytest.raises(foranav_model.ModelFormatError, match="not a ForaNav model"):
        foranav_model.load_model(saved({"x": np.zeros(3)}))
    with pytest.raises(foranav_model.ModelFormatError, match="not an .npz archive"):
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


def test_that_a_format_2_model_is_refused_naming_its_version():
    arrays = make_model().to_arrays()
    arrays["format_version"] = np.array(2, np.int32)
    with pytest.raises(foranav_model.ModelFormatError, match="model format version 2, this detector reads version 3"):
        foranav_model.load_model(saved(arrays))


def test_that_several_imageries_round_trip_with_their_own_colour_models_and_thresholds():
    rng = np.random.RandomState(1)
    domains = [foranav_model.Domain(name, svm, 0.5 + svm, 0.001, rng.rand(2, 512), 0.0, rng.rand(512))
               for name, svm in (("survey", -0.5), ("uav", 0.25))]
    model = make_model(domains=domains, crown_ratios=(0.95, 1.1, 1.3), provenance="site A (CC-BY 4.0)")
    loaded = foranav_model.load_model(saved(model))
    assert [d.name for d in loaded.domains] == ["survey", "uav"]
    assert loaded.domain("uav").svm_threshold == pytest.approx(0.25)
    assert np.array_equal(loaded.domain("survey").colour_vectors, domains[0].colour_vectors.astype(np.float32))
    assert loaded.crown_ratios == pytest.approx((0.95, 1.1, 1.3)) and loaded.provenance == "site A (CC-BY 4.0)"
    with pytest.raises(foranav_model.ModelFormatError, match="no domain 'x'.*survey, uav"):
        loaded.domain("x")


def _damaged_files(tmp_path):
    """{kind: path} of files that are not usable models, made from a good one."""
    good = saved(make_model()).getvalue()
    files = {"truncated": good[:4000], "empty": b"", "text": b"species = oil_palm\n",
             "lfs pointer": b"version https://git-lfs.github.com/spec/v1\noid sha256:abc\nsize 8123\n"}
    crc = bytearray(good)
    position = good.index(b"svm_weights.npy") + 200  # inside the stored array's bytes
    crc[position] ^= 0xFF
    files["crc damaged"] = bytes(crc)
    npy = io.BytesIO()
    np.save(npy, np.zeros(3))
    files["npy"] = npy.getvalue()
    arrays = make_model().to_arrays()
    arrays["svm_weights"] = np.array(["a"] * arrays["svm_weights"].size)
    files["wrong field type"] = saved(arrays).getvalue()
    arrays = make_model().to_arrays()
    arrays["species"] = np.array(3.5)
    files["wrong species type"] = saved(arrays).getvalue()
    paths = {}
    for kind, data in files.items():
        paths[kind] = tmp_path / (kind.replace(" ", "_") + ".npz")
        paths[kind].write_bytes(data)
    return paths


def test_that_damaged_model_files_give_one_line_that_never_suggests_unpickling(tmp_path):
    for kind, path in _damaged_files(tmp_path).items():
        with pytest.raises(foranav_model.ModelFormatError) as caught:
            foranav_model.load_model(str(path))
        message = str(caught.value)
        assert str(path) in message and "\n" not in message, kind
        assert "pickle" not in message.lower(), (kind, message)
    assert "git lfs pull" in str(pytest.raises(foranav_model.ModelFormatError, foranav_model.load_model,
                                                 str(tmp_path / "lfs_pointer.npz")).value)


def test_that_detect_with_a_damaged_model_exits_2_with_one_line(tmp_path, capsys):
    import cv2
    from host_tools.cli import main
    from host_tools.detection import synthetic
    image = tmp_path / "frame.png"
    cv2.imwrite(str(image), synthetic.scene(1)[0])
    for kind, path in _damaged_files(tmp_path).items():
        assert main(["detect", "--model", str(path), str(image)]) == 2, kind
        err = capsys.readouterr().err.strip()
        assert err.count("\n") == 0 and "Traceback" not in err and "pickle" not in err.lower(), (kind, err)
