"""Rendered datasets: the crop protocol holds, annotations load with the one loader, same seed same bytes."""
import csv
import math
import subprocess
import sys

import numpy as np
import pytest

from host_tools.annotations import read_boxes, boxes_by_image
from host_tools.plantation import TOUCH_TOLERANCE_M
from host_tools.sim.dataset import crop_candidates, generate, random_scene, _contains
from host_tools.sim.world import TreeInView

COUNT = 6
MM = 1e-3  # tree positions are compared to the millimetre
ORIGINAL_SEED_12_TREES = 11
ORIGINAL_SEED_12_CHECKSUM = 9.617629


def synth(out, seed, *extra):
    return subprocess.run([sys.executable, "-m", "host_tools.cli", "synth", "--out", str(out), "--count",
                           str(COUNT), "--seed", str(seed), *extra], capture_output=True, text=True)


def tree_files(root):
    return {p.relative_to(root).as_posix(): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    root = tmp_path_factory.mktemp("synth")
    proc = synth(root / "a", 3)
    assert proc.returncode == 0, proc.stderr
    return root


def test_that_synth_with_the_same_seed_writes_identical_bytes(dataset):
    proc = synth(dataset / "b", 3)
    assert proc.returncode == 0, proc.stderr
    first, second = tree_files(dataset / "a"), tree_files(dataset / "b")
    assert first.keys() == second.keys() and len(first) > 2 * COUNT
    assert first == second


def test_that_a_different_seed_gives_different_images(dataset):
    proc = synth(dataset / "c", 4)
    assert proc.returncode == 0, proc.stderr
    assert tree_files(dataset / "a")["frames/00000.png"] != tree_files(dataset / "c")["frames/00000.png"]


def test_that_the_layout_and_csvs_are_as_documented(dataset):
    root = dataset / "a"
    rows = list(csv.DictReader((root / "crops" / "crops.csv").open()))
    assert [r["class"] for r in rows].count("pos") == COUNT
    assert [r["class"] for r in rows].count("neg") == COUNT
    assert all((root / "crops" / r["image"]).exists() for r in rows)
    assert {r["category"] for r in rows if r["class"] == "pos"} == {"oil_palm"}
    assert all(r["category"] != "oil_palm" for r in rows if r["class"] == "neg")
    boxes = read_boxes(root / "frames" / "boxes.csv")
    frames = boxes_by_image(boxes)
    assert len(frames) == COUNT and all((root / "frames" / name).exists() for name in frames)
    labels = {b.label for b in boxes if not b.is_empty_marker}
    assert labels <= {"oil_palm", "coconut", "date_palm", "citrus", "olive", "roof", "road_cross"}
    for b in boxes:  # only complete trees are annotated: every box lies inside its 352x288 frame
        x0, y0, x1, y1 = b.corners()
        assert b.is_empty_marker or (x0 >= -0.01 and y0 >= -0.01 and x1 <= 352.01 and y1 <= 288.01)


def test_that_the_species_option_selects_the_target():
    positives, negatives, _ = generate(seed=5, count=4, frame_count=0, target_species=("citrus",))
    assert {c.category for c in positives} == {"citrus"}
    assert "citrus" not in {c.category for c in negatives}


def test_that_positive_crops_hold_exactly_one_complete_target_and_negatives_none():
    # Fixture: a frame with two target trees side by side and one look-alike
    image = np.zeros((288, 352, 3), np.uint8)
    trees = [TreeInView(1, "oil_palm", True, 100, 144, 80, 80, True),
             TreeInView(2, "oil_palm", True, 190, 144, 80, 80, True),
             TreeInView(3, "coconut", False, 290, 144, 80, 80, True)]
    rng = np.random.default_rng(0)
    # Test
    crops = [c for _ in range(30) for c in crop_candidates(rng, image, trees, [], ("oil_palm",), 0)]
    # Assert
    assert any(c.positive for c in crops) and any(not c.positive for c in crops)
    for c in crops:
        inside = [t for t in trees[:2] if _contains(c.window, t)]
        assert len(inside) == (1 if c.positive else 0)
        assert c.image.shape[:2] == (c.window[2], c.window[2])


def test_that_a_bad_count_is_one_line_and_nonzero(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "host_tools.cli", "synth", "--out", str(tmp_path / "x"),
                           "--count", "0"], capture_output=True, text=True)
    assert proc.returncode == 2 and proc.stderr.strip().count("\n") == 0 and "--count" in proc.stderr
    assert not (tmp_path / "x").exists()


def touching_partner(tree, trees):
    """The tree of the same row whose crown meets this one's (centre distance = sum of radii + tolerance)."""
    for other in trees:
        gap = math.hypot(tree.x - other.x, tree.y - other.y) - (tree.crown_m + other.crown_m) / 2.0
        if other is not tree and abs(other.y - tree.y) < MM and -MM <= gap <= TOUCH_TOLERANCE_M + MM:
            return other
    return None


def touching_share(touching_rate):
    trees = [scene.trees for seed in range(8)
             for scene in [random_scene(np.random.default_rng(seed), ("oil_palm",), touching_rate=touching_rate)]]
    return np.mean([touching_partner(t, row) is not None for row in trees for t in row])


def test_that_the_touching_option_puts_crowns_against_their_row_neighbour():
    # with rate 1 every tree after the first of its row touches the previous one (objects may remove a few)
    assert touching_share(1.0) > 0.8
    assert touching_share(None) < 0.2


def test_that_without_the_touching_option_the_scenes_are_the_original_ones():
    # Fixture: the first scene of `foranav synth --seed 12` as the generator drew it before the option existed
    scene = random_scene(np.random.default_rng([12, 2024]), ("oil_palm",))
    # Assert
    assert len(scene.trees) == ORIGINAL_SEED_12_TREES
    assert round(sum(t.x + 2 * t.y + 3 * t.crown_m for t in scene.trees), 6) == ORIGINAL_SEED_12_CHECKSUM
