"""foranav bench recall / detector --grouping: the period-tied peak stage beside today's grouping."""
import json

from host_tools import cli
from host_tools.detection import bench, recall_bench


def test_that_bench_recall_runs_the_module_with_the_grouping_asked_for(capsys):
    assert cli.main(["bench", "recall", "--count", "1", "--seed", "3", "--grouping", "period", "--json"]) == 0
    printed = json.loads(capsys.readouterr().out)["recall"]
    assert printed["grouping"] == "period" and len(printed["cases"]) == len(recall_bench.CASES)
    assert recall_bench.measure("oil_palm", count=1, seed=3)["grouping"] == "nms"  # the default: today's


def test_that_bench_detector_times_the_grouping_asked_for():
    result = bench.measure(seed=0, sizes=((352, 288),), fast_frames={352: 3}, reference_frames=1, grouping="period")
    assert result["grouping"] == "period" and result["sizes"]["352x288"]["median_ms"] > 0
