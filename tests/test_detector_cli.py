"""foranav detect / train / evaluate / bench detector: outputs and one-line errors."""
import json

import cv2
import numpy as np

import host_tools.detection  # noqa: F401
import foranav_model
from host_tools import annotations
from host_tools.cli import main
from host_tools.detection import bench, common, synthetic


def write_dataset(folder, seeds):
    """Synthetic frames + boxes CSV in the shared annotation format."""
    folder.mkdir(parents=True, exist_ok=True)
    boxes = []
    for seed in seeds:
        image, palms, roofs = synthetic.scene(seed, diameter=(65, 130))
        name = "%d.png" % seed
        cv2.imwrite(str(folder / name), image)
        boxes += [annotations.Box(name, cx, cy, d, d, "oil_palm") for cx, cy, d in palms]
        boxes += [annotations.Box(name, cx, cy, d, d * 0.7, "roof") for cx, cy, d in roofs]
    annotations.write_boxes(folder / "boxes.csv", boxes)
    return folder / "boxes.csv"


def one_error_line(capsys):
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "error" in err[0]
    return err[0]


def test_that_detect_prints_one_json_object_per_image(tmp_path, capsys):
    paths = []
    for seed in (1, 2):
        paths.append(str(tmp_path / ("%d.png" % seed)))
        cv2.imwrite(paths[-1], synthetic.scene(seed)[0])
    assert main(["detect"] + paths + ["--json"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert len(lines) == 2
    for path, line in zip(paths, lines):
        record = json.loads(line)
        assert record["image"] == path and (record["width"], record["height"]) == (352, 288)
        for d in record["detections"]:
            assert set(d) == {"x", "y", "w", "h", "score"}


def test_that_an_unreadable_image_is_one_error_line(tmp_path, capsys):
    bad = tmp_path / "bad.png"
    bad.write_bytes(b"not a png")
    assert main(["detect", str(bad), "--json"]) == 2
    assert "cannot read image" in one_error_line(capsys)
    assert capsys.readouterr().out == ""


def test_that_a_model_of_another_version_is_one_error_line(tmp_path, capsys):
    image = tmp_path / "f.png"
    cv2.imwrite(str(image), synthetic.scene(3)[0])
    arrays = dict(np.load(common.model_path("oil_palm"), allow_pickle=False))
    arrays["format_version"] = np.array(99)
    model = tmp_path / "old.npz"
    np.savez(str(model), **arrays)
    assert main(["detect", str(image), "--model", str(model)]) == 2
    assert "format version 99" in one_error_line(capsys)


def test_that_a_window_larger_than_the_frame_is_one_error_line(tmp_path, capsys):
    image = tmp_path / "f.png"
    cv2.imwrite(str(image), synthetic.scene(4)[0])
    assert main(["detect", str(image), "--window", "400"]) == 2
    assert "larger than the 352x288 frame" in one_error_line(capsys)


def test_that_training_on_an_empty_csv_is_one_error_line(tmp_path, capsys):
    empty = tmp_path / "empty.csv"
    empty.write_text("")
    assert main(["train", "--species", "oil_palm", "--data", str(empty), "--out", str(tmp_path / "m.npz")]) == 2
    assert "empty CSV" in one_error_line(capsys)
    assert not (tmp_path / "m.npz").exists()


def test_that_training_is_reproducible_from_its_seed_and_evaluation_reports_the_paper_protocol(tmp_path, capsys):
    train_csv = write_dataset(tmp_path / "train", range(300, 330))
    test_csv = write_dataset(tmp_path / "test", range(900, 910))
    outputs = [tmp_path / "a.npz", tmp_path / "b.npz"]
    for out in outputs:
        assert main(["train", "--species", "oil_palm", "--data", str(train_csv), "--seed", "5", "--out", str(out),
                     "--quiet"]) == 0
    assert outputs[0].read_bytes() == outputs[1].read_bytes()
    assert foranav_model.load_model(str(outputs[0])).seed == 5
    capsys.readouterr()
    assert main(["evaluate", "--model", str(outputs[0]), "--data", str(test_csv), "--crops", "15", "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert {"accuracy", "precision", "recall", "n_pos", "n_neg", "frames"} <= set(result)
    assert 0 < result["n_pos"] <= 15 and 0 < result["n_neg"] <= 15
    assert {"precision", "recall", "f1", "centre_error_px_mean"} <= set(result["frames"])
    assert result["frames"]["n_frames"] == 10


def test_that_the_benchmark_reports_every_figure_the_issue_asks_for():
    result = bench.measure(seed=0, sizes=((352, 288),), fast_frames={352: 5}, reference_frames=1)
    figures = result["sizes"]["352x288"]
    assert {"median_ms", "p90_ms", "fps", "speedup_vs_reference"} <= set(figures)
    assert figures["median_ms"] > 0 and figures["speedup_vs_reference"] > 1
    assert result["peak_rss_mb"] > 0
