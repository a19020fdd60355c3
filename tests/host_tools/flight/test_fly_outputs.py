"""A flight's record is on disk before its plot is drawn, and the plot of a large map stays one artist for the
crowns (ids drawn only on small maps): `foranav fly` on a 1000-tree map used to spend its time drawing."""
import dataclasses
import json

import pytest

from host_tools.flight import OracleCamera, run_flight
from host_tools.flight import plot as flight_plot
from host_tools.maps import load_map
from host_tools.plotting import plt


def test_that_summary_json_and_the_tlog_are_written_before_the_plot(tmp_path, monkeypatch):
    pmap = load_map("map1")
    seen = {}

    def plot_that_fails(flight, path):
        out = tmp_path / "out"
        seen["files"] = sorted(p.name for p in out.iterdir())
        seen["summary"] = json.loads((out / "summary.json").read_text())
        raise RuntimeError("the plot broke")

    monkeypatch.setattr(flight_plot, "plot_trajectory", plot_that_fails)
    with pytest.raises(RuntimeError, match="the plot broke"):
        run_flight(pmap, OracleCamera(pmap, seed=1), seed=1, out_dir=tmp_path / "out")
    assert {"flight.tlog", "summary.json"} <= set(seen["files"]) and "trajectory.png" not in seen["files"]
    assert seen["summary"]["plot"].endswith("trajectory.png") and seen["summary"]["targets"] == [1, 2, 3, 4, 5, 6]


def _with_trees(pmap, count):
    extra = [dataclasses.replace(pmap.trees[-1], id=1000 + i, x=10.0 + i % 40, y=5.0 + i // 40, target=False)
             for i in range(count - len(pmap.trees))]
    return dataclasses.replace(pmap, trees=list(pmap.trees) + extra)


@pytest.mark.parametrize("trees, labels", [(7, 7), (flight_plot.MAX_LABELLED_TREES, flight_plot.MAX_LABELLED_TREES),
                                           (flight_plot.MAX_LABELLED_TREES + 1, 0)])
def test_that_the_crowns_are_one_collection_and_ids_are_drawn_on_small_maps_only(trees, labels):
    pmap = _with_trees(load_map("map1"), trees)
    fig, ax = plt.subplots()
    flight_plot.draw_trees(ax, pmap, {1}, photos=False)
    assert len(ax.collections) == 1 and len(ax.collections[0].get_paths()) == trees and not ax.patches
    assert len(ax.texts) == labels
    x_min, x_max = ax.get_xlim()
    assert x_min < min(t.x for t in pmap.trees) and x_max > max(t.x for t in pmap.trees)
    plt.close(fig)
