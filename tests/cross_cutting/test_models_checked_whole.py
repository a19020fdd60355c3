"""A model is checked whole wherever it enters (issue 45): its network runs in OpenCV, its windows fit the camera's
frames; a flight whose camera reported no tree is not completed; a bad --report/--plot costs no model."""
import json
from pathlib import Path

import numpy as np
import pytest

from host_tools import cli
import host_tools.detection  # noqa: F401  (puts the camera module folder on sys.path)
from host_tools.jevois_host import DEFAULT_MODULE_DIR

import foranav_model

SHIPPED = Path(DEFAULT_MODULE_DIR)
OLD_BYTES = b"an earlier model\n"


def _variant(path, source="foranav_oil_palm_cnn.npz", **arrays):
    data = foranav_model.load_model(str(SHIPPED / source)).to_arrays()
    data.update(arrays)
    with open(path, "wb") as handle:
        np.savez(handle, **data)
    return path


@pytest.fixture(scope="module")
def bad_models(tmp_path_factory):
    root = tmp_path_factory.mktemp("models")
    return {
        "garbage_network": _variant(root / "garbage_network.npz", cnn_onnx=np.frombuffer(b"not onnx" * 64, np.uint8)),
        "huge_windows": _variant(root / "huge_windows.npz", window_sizes=np.array([96, 10 ** 9], np.int32)),
        "window_past_frame": _variant(root / "window_past_frame.npz", window_sizes=np.array([96, 300], np.int32)),
        "tiny_reference": _variant(root / "tiny_reference.npz", reference_width=np.array(8, np.int32)),
        "huge_crown_ratio": _variant(root / "huge_crown_ratio.npz", crown_ratios=np.array([1.0, 1e9], np.float32)),
    }


REASONS = {"garbage_network": "cnn_onnx: the network does not run in OpenCV",
           "huge_windows": "window_sizes up to 1000000000 px do not fit the camera's frames",
           "window_past_frame": "window_sizes up to 300 px do not fit",
           "tiny_reference": "reference_width 8 px", "huge_crown_ratio": "crown_ratios must be in"}


@pytest.mark.parametrize("kind", sorted(REASONS))
def test_that_the_model_reader_refuses_a_model_the_camera_cannot_run(kind, bad_models):
    with pytest.raises(foranav_model.ModelFormatError, match=REASONS[kind]) as caught:
        foranav_model.load_model(str(bad_models[kind]))
    assert str(bad_models[kind]) in str(caught.value) and "\n" not in str(caught.value)


def test_that_every_shipped_model_passes_the_whole_check():
    for path in sorted(SHIPPED.glob("*.npz")):
        foranav_model.load_model(str(path))


def _module_copy(root, model):
    folder = root / "ForaNavTrees"
    folder.mkdir(parents=True)
    for path in SHIPPED.iterdir():
        if path.is_file():
            (folder / path.name).write_bytes(path.read_bytes())
    (folder / "foranav_oil_palm_cnn.npz").write_bytes(model.read_bytes())
    return folder


def _entries(model, folder, tmp):
    """Every command a model enters by (argv), for one bad model."""
    return [["detect", "--model", str(model), str(tmp / "frame.png")],
            ["evaluate", "--model", str(model), "--data", str(tmp / "boxes.csv")],
            ["fly", "--map", "map1", "--model", str(model), "--out", str(tmp / "fly")],
            ["sweep", "--count", "1", "--model", str(model), "--out", str(tmp / "sweep")],
            ["bench", "recall", "--model", str(model), "--count", "1"],
            ["bench", "detector", "--model", str(model)],
            ["paper-tests", "--model", str(model), "--out", str(tmp / "paper")],
            ["package", "--out", str(tmp / "m.jvpkg"), "--module-dir", str(folder)]]


@pytest.mark.parametrize("kind", ["garbage_network", "huge_windows"])
def test_that_every_command_a_model_enters_by_refuses_it_with_one_line(kind, bad_models, tmp_path, capsys):
    # Fixture: the bad model alone, and as the module folder's network model
    model = bad_models[kind]
    folder = _module_copy(tmp_path / "module", model)
    before = sorted(p.name for p in tmp_path.iterdir())
    for argv in _entries(model, folder, tmp_path):
        # Test
        code = cli.main(argv)
        # Assert
        err = capsys.readouterr().err.splitlines()
        assert code == 2 and len(err) == 1, (argv, err)
        assert REASONS[kind] in err[0] and ("foranav_oil_palm_cnn.npz" in err[0] or model.name in err[0]), err
    assert sorted(p.name for p in tmp_path.iterdir()) == before


def test_that_a_deploy_refuses_a_module_whose_model_cannot_run(bad_models, tmp_path, capsys):
    from tests.host_tools.deploy.conftest import make_card
    folder = _module_copy(tmp_path / "module", bad_models["garbage_network"])
    sd = make_card(tmp_path)
    code = cli.main(["deploy", "--sd", str(sd), "--module-dir", str(folder)])
    err = capsys.readouterr().err.splitlines()
    assert code == 2 and len(err) == 1 and "model file foranav_oil_palm_cnn.npz" in err[0], err
    assert not (sd / "modules" / "ForaNav").exists()


def test_that_a_flight_whose_camera_saw_no_tree_is_not_completed(tmp_path, capsys):
    # Fixture: a valid model that never fires (its SVM threshold beyond any score), a short column of trees
    model = foranav_model.load_model(str(SHIPPED / "foranav_oil_palm.npz"))
    for domain in model.domains:
        domain.svm_threshold = 1e6
    with open(tmp_path / "blind.npz", "wb") as handle:
        foranav_model.save_model(model, handle)
    data = json.loads((Path(cli.__file__).parent / "data" / "maps" / "map1.json").read_text())
    data["waypoints"] = [[0.3, 0.45], [2.0, 0.45]]
    (tmp_path / "short.json").write_text(json.dumps(data))
    # Test
    code = cli.main(["fly", "--map", str(tmp_path / "short.json"), "--model", str(tmp_path / "blind.npz"),
                     "--out", str(tmp_path / "out"), "--json"])
    # Assert
    summary = json.loads(capsys.readouterr().out)
    assert code == 1
    assert summary["camera_blind"] and not summary["completed"] and summary["detections"] == 0
    assert summary["targets"]


def test_that_a_flight_that_saw_trees_is_not_called_blind(capsys, tmp_path):
    code = cli.main(["fly", "--map", "map1", "--camera", "oracle", "--out", str(tmp_path), "--json"])
    summary = json.loads(capsys.readouterr().out)
    assert code == 0 and summary["completed"] and not summary["camera_blind"] and summary["detections"] > 0


@pytest.mark.parametrize("report", ["afile", "afile/sub", "existing_model.npz"])
def test_that_a_bad_report_folder_costs_no_model(report, tmp_path, capsys):
    # Fixture: an earlier model, and a --report that cannot be a folder
    (tmp_path / "keep.npz").write_bytes(OLD_BYTES)
    (tmp_path / "afile").write_bytes(OLD_BYTES)
    (tmp_path / "existing_model.npz").write_bytes(OLD_BYTES)
    (tmp_path / "boxes.csv").write_text("image,x_center,y_center,width,height,label\n")
    # Test
    code = cli.main(["train", "--species", "oil_palm", "--data", str(tmp_path / "boxes.csv"),
                     "--out", str(tmp_path / "keep.npz"), "--report", str(tmp_path / report)])
    # Assert
    err = capsys.readouterr().err.splitlines()
    assert code == 2 and len(err) == 1 and "--report" in err[0], err
    assert (tmp_path / "keep.npz").read_bytes() == OLD_BYTES


@pytest.mark.parametrize("plot, named", [("pr.bmpx", "a figure is written as"), ("afile/pr.png", "--plot"),
                                         ("folder", "is a folder"), ("no_dir/pr.png", "does not exist")])
def test_that_a_bad_plot_path_is_refused_before_the_evaluation(plot, named, tmp_path, capsys):
    (tmp_path / "afile").write_bytes(OLD_BYTES)
    (tmp_path / "folder").mkdir()
    code = cli.main(["evaluate", "--model", "oil_palm", "--data", str(tmp_path / "missing.csv"),
                     "--plot", str(tmp_path / plot)])
    err = capsys.readouterr().err.splitlines()
    assert code == 2 and len(err) == 1 and named in err[0] and "--plot" in err[0], err


def test_that_a_file_name_of_300_characters_is_refused_and_a_long_valid_one_written(tmp_path, capsys):
    long_ok = "m" * 250 + ".png"  # a valid name: its temporary file's name must fit too
    assert cli.main(["render", "--map", "map1", "--x", "1", "--y", "0", "--out", str(tmp_path / long_ok)]) == 0
    assert (tmp_path / long_ok).stat().st_size > 0
    capsys.readouterr()
    code = cli.main(["render", "--map", "map1", "--x", "1", "--y", "0", "--out", str(tmp_path / ("n" * 300 + ".png"))])
    err = capsys.readouterr().err.splitlines()
    assert code == 2 and len(err) == 1 and "a name of 304 bytes" in err[0], err
    assert sorted(p.name for p in tmp_path.iterdir()) == [long_ok]


@pytest.mark.parametrize("shape, gsd", [((1, 100000), "0.01"), ((100, 100), "1e9")])
def test_that_a_ground_photo_of_any_shape_or_scale_renders_within_the_grounds_size(shape, gsd, tmp_path):
    # a 100000 x 1 px strip asked numpy for 40 GiB; a gsd of 1e9 made OpenCV refuse its own size (issue 45)
    import cv2
    cv2.imwrite(str(tmp_path / "ground.png"), np.full(shape + (3,), 90, np.uint8))
    assert cli.main(["render", "--map", "map1", "--x", "1", "--y", "0", "--ground", str(tmp_path / "ground.png"),
                     "--ground-gsd", gsd, "--out", str(tmp_path / "frame.png")]) == 0
    assert cv2.imread(str(tmp_path / "frame.png")).shape == (288, 352, 3)


def test_that_a_sweep_leaves_no_dask_files_in_tmpdir(tmp_path, monkeypatch):
    import tempfile
    pytest.importorskip("dask.distributed")
    monkeypatch.setenv("TMPDIR", str(tmp_path / "tmp"))
    (tmp_path / "tmp").mkdir()
    monkeypatch.setattr(tempfile, "tempdir", None)  # re-read TMPDIR
    assert cli.main(["sweep", "--count", "1", "--workers", "1", "--camera", "oracle", "--out",
                     str(tmp_path / "sweep")]) == 0
    assert list((tmp_path / "tmp").iterdir()) == []
