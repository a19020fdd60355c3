"""foranav detect / train / evaluate / bench detector: outputs and one-line errors."""
import json

import cv2
import numpy as np
import pytest

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
    assert "bad.png: not an image" in one_error_line(capsys)
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
    report = (tmp_path / "a_report" / "report.md").read_text()  # next to the model, per imagery and cue
    assert "| train | oil_palm (target) |" in report and (tmp_path / "a_report" / "cues.png").stat().st_size > 0
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
    network = result["sizes"]["352x288 with network"]
    for row in (figures, network):  # the A33 estimate: host CPU time x the measured factor
        assert row["a33_ms"] == pytest.approx(row["cpu_median_ms"] * bench.A33_FACTOR, rel=0.01, abs=0.1)


def crowded_scene(tmp_path, palms=14):
    image, placed, _roofs = synthetic.scene(21, width=900, height=700, palms=palms, roofs=0, diameter=(85, 100))
    path = tmp_path / "crowded.png"
    cv2.imwrite(str(path), image)
    return str(path), placed


def test_that_detect_reports_every_tree_by_default_and_max_detections_caps(tmp_path, capsys):
    path, placed = crowded_scene(tmp_path)
    assert len(placed) > detector_core_default_cap()
    assert main(["detect", path, "--crown-px", "92", "--json"]) == 0
    every = json.loads(capsys.readouterr().out)["detections"]
    assert len(every) > detector_core_default_cap()  # the camera's maxtrees is not a host limit
    assert main(["detect", path, "--crown-px", "92", "--max-detections", "3", "--json"]) == 0
    capped = json.loads(capsys.readouterr().out)["detections"]
    assert capped == every[:3]


def detector_core_default_cap():
    import foranav_detector
    return foranav_detector.DEFAULT_MAX_DETECTIONS


def test_that_the_crown_size_sets_the_windows_and_gsd_with_crown_metres_is_the_same(tmp_path, capsys):
    path, _placed = crowded_scene(tmp_path, palms=3)
    model = common.load("oil_palm")
    assert main(["detect", path, "--crown-px", "92", "--json"]) == 0
    by_pixels = json.loads(capsys.readouterr().out)
    assert by_pixels["windows"] == [round(92 * r) for r in model.crown_ratios]
    assert main(["detect", path, "--gsd", "0.1", "--crown-m", "9.2", "--json"]) == 0
    assert json.loads(capsys.readouterr().out) == by_pixels


def test_that_an_image_of_no_camera_size_without_a_scale_gets_a_one_line_warning(tmp_path, capsys):
    path, _placed = crowded_scene(tmp_path, palms=2)
    assert main(["detect", path]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "warning" in err[0] and "--crown-px" in err[0]
    assert main(["detect", path, "--crown-px", "90"]) == 0
    assert capsys.readouterr().err == ""


def test_that_an_unknown_domain_and_half_a_scale_are_one_error_line(tmp_path, capsys):
    path, _placed = crowded_scene(tmp_path, palms=1)
    assert main(["detect", path, "--domain", "nowhere"]) == 2
    assert "no domain 'nowhere'" in one_error_line(capsys)
    assert main(["detect", path, "--gsd", "0.1"]) == 2
    assert "--crown-m" in one_error_line(capsys)
