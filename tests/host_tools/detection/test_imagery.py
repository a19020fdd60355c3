"""Imageries of different colour: one shared SVM, a colour model and thresholds per imagery (issue 9)."""
import cv2
import numpy as np
import pytest

import host_tools.detection  # noqa: F401
from host_tools.annotations import Box, write_boxes
from host_tools.cli import main
from host_tools.detection import common, dataset, evaluation, synthetic, training

import foranav_detector as detector_core

CHANNELS_B = [1, 2, 0]  # imagery B = A's frames with the colour channels cycled: same value channel (SVM,
CHANNELS_B_INVERSE = [2, 0, 1]  # texture), clearly different hues (palms blue on green ground)
MIN_PRECISION = 0.9
MIN_RECALL = 0.6


def two_colour_frames(seeds, imagery_b):
    """Frames with two palms (oil_palm), a roof and a look-alike: a palm in the OTHER imagery's palm colours
    (coconut), which only a colour model per imagery can reject."""
    out = []
    for seed in seeds:
        image, palms, roofs = synthetic.scene(seed, palms=3, roofs=1, diameter=(70, 120))
        boxes = [Box("%d.png" % seed, cx, cy, d, d, "oil_palm") for cx, cy, d in palms[:2]]
        if len(palms) == 3:
            cx, cy, d = palms[2]
            mask = np.zeros(image.shape[:2], np.uint8)
            cv2.circle(mask, (int(cx), int(cy)), int(d / 2), 255, -1)
            other = image[:, :, CHANNELS_B_INVERSE if imagery_b else CHANNELS_B]
            image = np.where(mask[..., None] > 0, other, image)
            boxes.append(Box("%d.png" % seed, cx, cy, d, d, "coconut"))
        boxes += [Box("%d.png" % seed, cx, cy, d, d * 0.7, "roof") for cx, cy, d in roofs]
        if imagery_b:
            image = np.ascontiguousarray(image[:, :, CHANNELS_B])
        out.append(dataset.Frame("%d.png" % seed, image, boxes))
    return out


def frame_figures(model, frames):
    return evaluation.evaluate_frames(model, frames, detector_core.DetectorSettings(max_detections=None))


def test_that_a_model_with_a_colour_model_per_imagery_detects_palms_in_both_and_one_template_does_not():
    # Fixture: imagery A (16 frames) and B (8 frames, other colours), held-out frames of each
    train_a, train_b = two_colour_frames(range(2000, 2016), False), two_colour_frames(range(3000, 3008), True)
    test_a, test_b = two_colour_frames(range(4000, 4008), False), two_colour_frames(range(5000, 5008), True)
    # Test
    per_imagery = training.train([training.Imagery("a", train_a), training.Imagery("b", train_b)], "oil_palm", seed=3)
    single = training.train(train_a + train_b, "oil_palm", seed=3)  # one imagery: one template for both
    # Assert: each held-out imagery is scored with its own domain, and both are detected
    for name, frames in (("a", test_a), ("b", test_b)):
        result = frame_figures(per_imagery, frames)
        assert result["domains"] == {name: len(frames)}
        assert result["precision"] >= MIN_PRECISION and result["recall"] >= MIN_RECALL, (name, result)
    single_results = [frame_figures(single, frames) for frames in (test_a, test_b)]
    assert not all(r["precision"] >= MIN_PRECISION and r["recall"] >= MIN_RECALL for r in single_results)


def write_imagery(folder, seeds, imagery_b):
    folder.mkdir(parents=True)
    boxes = []
    for frame in two_colour_frames(seeds, imagery_b):
        cv2.imwrite(str(folder / frame.path), frame.bgr)
        boxes += frame.boxes
    write_boxes(folder / "boxes.csv", boxes)
    return str(folder / "boxes.csv")


def test_that_train_with_data_listed_once_or_repeated_writes_the_same_model_bytes(tmp_path):
    csv_a = write_imagery(tmp_path / "site_a", range(10, 18), False)
    csv_b = write_imagery(tmp_path / "site_b", range(20, 24), True)
    train_args = ["train", "--species", "oil_palm", "--seed", "2", "--quiet", "--report", "none"]
    assert main(train_args + ["--data", csv_a, csv_b, "--out", str(tmp_path / "listed.npz")]) == 0
    assert main(train_args + ["--data", csv_a, "--data", csv_b, "--out", str(tmp_path / "repeated.npz")]) == 0
    listed = (tmp_path / "listed.npz").read_bytes()
    assert listed == (tmp_path / "repeated.npz").read_bytes()
    model = common.load(str(tmp_path / "listed.npz"))
    assert [d.name for d in model.domains] == ["site_a", "site_b"]  # both CSVs, each its own imagery


def test_that_evaluate_with_repeated_data_scores_every_csv(tmp_path, capsys):
    csv_a = write_imagery(tmp_path / "site_a", range(30, 33), False)
    csv_b = write_imagery(tmp_path / "site_b", range(40, 42), True)
    model = training.train(two_colour_frames(range(2000, 2010), False), "oil_palm", seed=1)
    path = tmp_path / "m.npz"
    import foranav_model
    foranav_model.save_model(model, str(path))
    plot = tmp_path / "pr.png"
    assert main(["evaluate", "--model", str(path), "--data", csv_a, "--data", csv_b, "--crops", "5", "--json",
                 "--plot", str(plot)]) == 0
    import json
    result = json.loads(capsys.readouterr().out)
    assert plot.stat().st_size > 0
    assert sorted(result["imageries"]) == sorted([csv_a, csv_b])
    assert result["frames"]["n_frames"] == 5
    assert set(result["imageries"][csv_a]["funnel"]) == set(evaluation.FUNNEL_STAGES)
    # the pooled figures carry the per-image false alarms too (the coconut target is judged on them)
    for key in ("false_alarms", "lookalike_false_alarms"):
        pooled = sum(r["n_" + key] for r in result["imageries"].values())
        assert result["frames"][key + "_per_image"] == pytest.approx(pooled / 5.0)


def test_that_the_report_warns_when_colour_alone_rejects_look_alikes_or_rejects_the_positives():
    from host_tools.detection import report
    rows = [{"imagery": "site_a", "label": "oil_palm", "target": True, "n": 50, "domain": "site_a", "svm": 0.9,
             "colour": 0.0, "texture": 0.95, "all": 0.0, "svm_texture": 0.9},
            {"imagery": "coconuts", "label": "coconut", "target": False, "n": 50, "domain": "site_a", "svm": 0.6,
             "colour": 0.0, "texture": 0.9, "all": 0.0, "svm_texture": 0.5},
            {"imagery": "site_a", "label": "roof", "target": False, "n": 50, "domain": "site_a", "svm": 0.05,
             "colour": 0.5, "texture": 0.1, "all": 0.0, "svm_texture": 0.02}]
    warnings = report.warnings_for(rows, [])
    assert any("colour rejects 100 % of the positives of site_a" in w for w in warnings)
    assert any("look-alikes of coconuts (coconut) are rejected by colour alone" in w and "imageries" in w
               for w in warnings)
    assert not any("roof" in w for w in warnings)
