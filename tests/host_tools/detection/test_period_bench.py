"""foranav bench recall / detector --grouping: the period-tied peak stage beside today's grouping."""
import json
import math

import numpy as np

from host_tools import cli
from host_tools.detection import bench, recall_bench
from host_tools.flight.vision_camera import VisionCamera

MAP_SPACING_TOLERANCE_PX = 1.0  # the projection of the map's spacing vs the rendered crowns' centres


def test_that_bench_recall_runs_the_module_with_the_grouping_asked_for(capsys):
    assert cli.main(["bench", "recall", "--count", "1", "--seed", "3", "--grouping", "period", "--json"]) == 0
    printed = json.loads(capsys.readouterr().out)["recall"]
    assert printed["grouping"] == "period" and len(printed["cases"]) == len(recall_bench.CASES)
    assert recall_bench.measure("oil_palm", count=1, seed=3)["grouping"] == "nms"  # the default: today's


def test_that_bench_detector_times_the_grouping_asked_for():
    result = bench.measure(seed=0, sizes=((352, 288),), fast_frames={352: 3}, reference_frames=1, grouping="period")
    assert result["grouping"] == "period" and result["sizes"]["352x288"]["median_ms"] > 0


def test_that_the_map_period_is_the_neighbours_distance_in_the_rendered_frame():
    rng = np.random.default_rng([3, 1])
    pmap = recall_bench._scene(rng, "touching")
    camera = VisionCamera(pmap, seed=1)
    pose = recall_bench._camera_pose(rng, "centre", pmap.altitude_m)
    target, neighbour = sorted(camera.render(pose).trees, key=lambda t: t.id)
    spacing = recall_bench._map_spacing_px(camera, pmap, pose[2])
    assert abs(spacing - math.hypot(neighbour.u - target.u, neighbour.v - target.v)) <= MAP_SPACING_TOLERANCE_PX
    result = recall_bench.measure("oil_palm", count=1, seed=3, grouping="period", period="map")
    assert (result["grouping"], result["period"]) == ("period", "map")
