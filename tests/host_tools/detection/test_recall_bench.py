"""foranav bench recall: the per-frame recall from straight above, by case (docs/detector.md)."""
import json

import numpy as np
import pytest

from host_tools import cli
from host_tools.detection import recall_bench
from host_tools.errors import ForaNavError


def test_that_the_recall_benchmark_is_seeded_and_covers_every_case(capsys):
    first = recall_bench.measure("oil_palm", count=2, seed=3)
    assert first == recall_bench.measure("oil_palm", count=2, seed=3)
    assert [(c["where"], c["case"]) for c in first["cases"]] == list(recall_bench.CASES)
    for case in first["cases"]:
        assert case["frames"] == 2 and 0.0 <= case["target_recall"] <= 1.0
        assert (case["neighbour_recall"] is None) == (case["case"] == "isolated")
    assert sum(row["frames"] for row in first["by_crown_px"]) <= 2 * len(recall_bench.CASES)
    assert cli.main(["bench", "recall", "--count", "1", "--seed", "3", "--json"]) == 0
    printed = json.loads(capsys.readouterr().out)["recall"]
    assert printed["frames_per_case"] == 1 and len(printed["cases"]) == len(recall_bench.CASES)


def test_that_the_small_crown_case_is_a_small_crown_touching_a_larger_one_high_up():
    rng = np.random.default_rng(0)
    for _ in range(20):
        pmap = recall_bench._scene(rng, "small")
        target, neighbour = pmap.trees
        assert 0.30 <= target.crown_m <= 0.34 <= neighbour.crown_m <= 0.45
        assert 1.3 <= pmap.altitude_m <= 1.5
        gap = abs(neighbour.x) - (target.crown_m + neighbour.crown_m) / 2
        assert abs(gap) <= 0.02 and neighbour.y == 0.0


def test_that_a_missing_model_is_one_error_before_any_frame():
    with pytest.raises(ForaNavError, match="no_such.npz"):
        recall_bench.measure("no_such.npz", count=1)
