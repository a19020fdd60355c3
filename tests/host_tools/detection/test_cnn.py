"""The learned stage (issue 35): a small CNN in the model file, run by OpenCV's dnn module on the camera.

The default suite needs no PyTorch: it uses the shipped foranav_oil_palm_cnn.npz (trained on rendered frames,
docs/detector.md says how). Training a network is opt-in (-m slow) and skipped without PyTorch."""
import io
import os
import sys

import cv2
import numpy as np
import pytest

import host_tools.detection  # noqa: F401  (camera module folder on sys.path)
from host_tools.cli import main
from host_tools.detection import common, synthetic, training
from host_tools.jevois_host import DEFAULT_MODULE_DIR

import foranav_cnn
import foranav_detector as detector_core
import foranav_features as features
import foranav_model

CNN_MODEL = "foranav_oil_palm_cnn.npz"
INPUT_TOLERANCE = 0.15  # the network's input after a change of light and gain (8-bit rounding and clipping)


def shipped_cnn_model():
    return common.load(os.path.join(DEFAULT_MODULE_DIR, CNN_MODEL))


def test_that_the_network_input_drops_the_light_and_the_camera_gain():
    bgr = synthetic.scene(21, palms=1, roofs=0)[0][60:180, 100:220]
    darker = cv2.convertScaleAbs(bgr, alpha=0.6, beta=10)
    one, other = (foranav_cnn.cnn_input(features.bgr_to_hsv(b)) for b in (bgr, darker))
    assert one.shape == (3, foranav_cnn.CNN_SIDE, foranav_cnn.CNN_SIDE) and one.dtype == np.float32
    assert abs(float(one.mean())) < 1e-3 and np.abs(one - other).mean() < INPUT_TOLERANCE


def test_that_a_model_with_a_network_round_trips_and_one_without_keeps_its_bytes():
    model = shipped_cnn_model()
    assert model.cnn_onnx and model.cnn_side == foranav_cnn.CNN_SIDE
    buffer = io.BytesIO()
    foranav_model.save_model(model, buffer)
    buffer.seek(0)
    loaded = foranav_model.load_model(buffer)
    assert loaded.cnn_onnx == model.cnn_onnx
    assert [d.cnn_threshold for d in loaded.domains] == [d.cnn_threshold for d in model.domains]
    assert "cnn_onnx" not in common.load("oil_palm").to_arrays()  # the other shipped models have none


def test_that_part_of_a_network_is_refused_in_one_line():
    arrays = shipped_cnn_model().to_arrays()
    del arrays["cnn_threshold"]
    with pytest.raises(foranav_model.ModelFormatError) as error:
        foranav_model.model_from_arrays(arrays, "m.npz")
    assert "network incomplete" in str(error.value) and "\n" not in str(error.value)
    arrays = shipped_cnn_model().to_arrays()
    arrays["cnn_onnx"] = arrays["cnn_onnx"].astype(np.float32)
    with pytest.raises(foranav_model.ModelFormatError, match="cnn_onnx has the wrong type"):
        foranav_model.model_from_arrays(arrays, "m.npz")


def test_that_the_network_threshold_decides_which_crowns_pass():
    model = shipped_cnn_model()
    frames = [synthetic.scene(seed, palms=2, roofs=1)[0] for seed in (31, 32, 33)]

    def found(threshold):
        detector = detector_core.TreeDetector(model, detector_core.DetectorSettings(cnn_threshold=threshold))
        return [detector.detect(frame) for frame in frames]
    every, none = found(-1e9), found(1e9)
    assert sum(map(len, every)) >= 3 and sum(map(len, none)) == 0
    without = foranav_model.model_from_arrays({k: v for k, v in model.to_arrays().items() if not k.startswith("cnn")})
    plain = [detector_core.TreeDetector(without).detect(frame) for frame in frames]
    assert every == plain  # a network that passes everything leaves the HOG path's detections


def test_that_training_a_network_without_pytorch_is_one_error_line(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "torch", None)  # as on a machine without the train extra
    out = tmp_path / "m.npz"
    assert main(["train", "--species", "oil_palm", "--cnn", "--data", "x.csv", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "PyTorch" in err[0] and not out.exists()


@pytest.mark.slow
def test_that_a_trained_network_is_the_same_bytes_from_the_same_seed_and_finds_the_palms():
    pytest.importorskip("torch")
    frames = synthetic.annotated_frames(range(600, 624), width=352, height=288)
    models = [training.train(frames, "oil_palm", seed=4, cnn=True) for _ in range(2)]
    assert models[0].cnn_onnx == models[1].cnn_onnx
    buffers = [io.BytesIO() for _ in models]
    for model, buffer in zip(models, buffers):
        foranav_model.save_model(model, buffer)
    assert buffers[0].getvalue() == buffers[1].getvalue()
    test = synthetic.annotated_frames(range(700, 708), width=352, height=288)
    detector = detector_core.TreeDetector(models[0], detector_core.DetectorSettings(max_detections=None))
    found = sum(1 for frame in test for d in detector.detect(frame.bgr)
                if any(abs(d.x - b.x_center) < b.width / 2 and abs(d.y - b.y_center) < b.height / 2
                       for b in frame.trees("oil_palm")))
    assert found >= 0.6 * sum(len(frame.trees("oil_palm")) for frame in test)
