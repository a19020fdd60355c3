"""The paper's Fig. 8: distance deviation from each reached target tree, per test, with the mean and its 95 %
confidence interval (matplotlib, Agg, PNG)."""
import os
from collections.abc import Sequence

from pymavlink import mavutil

from host_tools import fileio
from host_tools.flight.plot import save_map_figure, show_mosaic, zoom_to_content
from host_tools.flight.stats import mean_ci95
from host_tools.maps import PlantationMap
from host_tools.plotting import Circle, plt
from host_tools.sim.world import World

PAPER_BOUND_M = 0.10  # the paper: mean deviation below 0.1 m in every test
POINT_SPREAD = 0.18  # horizontal jitter of the per-tree points, deterministic (by rank)


def deviations_by_test(results: Sequence[dict]) -> list[tuple[int, list[float]]]:
    """[(test number, [deviation of each reached target, m])] from paper-test result entries."""
    out = []
    for entry in results:
        targets = set(entry["targets"])
        out.append((entry["test"], [r["deviation_m"] for r in entry["reached"] if r["id"] in targets]))
    return out


def plot_deviation(results: Sequence[dict], path: str | os.PathLike,
                   title: str = "Distance deviation from the target trees (simulated Tests 1-9)") -> None:
    """Write the Fig. 8-style plot of ``results`` (entries with "test", "targets", "reached") to ``path``."""
    data = deviations_by_test(results)
    fig, ax = plt.subplots(figsize=(8, 4.2), dpi=110)
    for position, (test, values) in enumerate(data):
        n = len(values)
        xs = [position - POINT_SPREAD + 2 * POINT_SPREAD * i / max(1, n - 1) for i in range(n)]
        ax.plot(xs, [100 * v for v in values], "o", color="#90a4ae", markersize=4,
                label="per tree" if position == 0 else None)
        mean, ci = mean_ci95(values)
        if mean is None:
            continue
        ax.errorbar([position], [100 * mean], yerr=[[100 * (ci or 0.0)], [100 * (ci or 0.0)]], fmt="s",
                    color="#1565c0", capsize=5, markersize=6, label="mean +/- 95 % CI" if position == 0 else None)
    ax.axhline(100 * PAPER_BOUND_M, color="#d32f2f", linestyle="--", linewidth=1,
               label="paper: mean < %.0f cm" % (100 * PAPER_BOUND_M))
    ax.set_xticks(range(len(data)))
    # a test that failed the paper's criteria (a missed or wrong tree) says so under its deviations
    ax.set_xticklabels(["Test %d%s" % (test, "" if entry.get("passed", True) else "\nFAIL")
                        for (test, _), entry in zip(data, results)])
    for label, entry in zip(ax.get_xticklabels(), results):
        if not entry.get("passed", True):
            label.set_color("#d32f2f")
    ax.set_ylabel("deviation (cm)")
    ax.set_ylim(0, max(ax.get_ylim()[1], 100 * PAPER_BOUND_M * 1.15))
    ax.set_title(title, fontsize=10)
    ax.grid(True, axis="y", linewidth=0.3)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=3, fontsize=8, frameon=False)
    fig.tight_layout()
    fileio.write_figure(fig, path)
    plt.close(fig)


TRACK_COLOURS = ("#1565c0", "#6a1b9a", "#00838f")
TREE_COLOURS = {"reached": "#2e7d32", "missed": "#ef6c00", "non_target": "#9e9e9e", "visited_non_target": "#d32f2f"}


def read_ground_truth_track(tlog_path: str | os.PathLike) -> list[tuple[float, float]]:
    """[(x, y)] of the MAV's true position (the tlog's DEBUG_VECT "gt_pos", NED -> Crazyflie FLU)."""
    log = mavutil.mavlink_connection(str(tlog_path), dialect="common")
    track = []
    try:
        while True:
            msg = log.recv_match(type="DEBUG_VECT")
            if msg is None:
                return track
            if msg.name.rstrip("\x00") == "gt_pos":
                track.append((msg.x, -msg.y))
    finally:
        log.close()


def plot_map_tests(pmap: PlantationMap, entries: Sequence[dict], tracks: Sequence[Sequence[tuple[float, float]]],
                   path: str | os.PathLike, world: World | None = None) -> None:
    """The paper's Figs. 6-7: one map with the flown trajectories of its tests overlaid.

    ``entries``: the tests' summaries (with "test", "reached", "missed_targets", "non_targets_visited");
    ``tracks``: per entry, [(x, y)] of the true trajectory. A target is green when every test reached it,
    orange when one missed it; a non-target is red when some test visited it. ``world`` (with photo crowns):
    its mosaic is drawn under the map, the trees outlined.
    """
    missed = {i for e in entries for i in e["missed_targets"]}
    visited_non_targets = {i for e in entries for i in e["non_targets_visited"]}
    fig, ax = plt.subplots(figsize=(8, 3.9), dpi=110)
    photos = world is not None and bool(world.photo_crowns)
    if photos:
        show_mosaic(ax, world)
        zoom_to_content(ax, pmap)
    for tree in pmap.trees:
        if tree.target:
            kind = "missed" if tree.id in missed else "reached"
        else:
            kind = "visited_non_target" if tree.id in visited_non_targets else "non_target"
        ax.add_patch(Circle((tree.x, tree.y), tree.crown_m / 2, facecolor="none" if photos else TREE_COLOURS[kind],
                            alpha=0.9 if photos else 0.3, edgecolor=TREE_COLOURS[kind],
                            linewidth=1.5 if photos else 1.0))
        label = str(tree.id) if tree.species == pmap.target_species else "%d %s" % (tree.id, tree.species)
        ax.annotate(label, (tree.x, tree.y + tree.crown_m / 2 + 0.03), ha="center", fontsize=7)
    for obj in pmap.objects:
        ax.add_patch(plt.Rectangle((obj.x - obj.size_m / 2, obj.y - obj.size_m / 2), obj.size_m, obj.size_m,
                                   facecolor="none", edgecolor="#795548", linestyle=":"))
        ax.annotate(obj.kind.replace("_", " "), (obj.x, obj.y), ha="center", va="center", fontsize=7)
    xs, ys = zip(*pmap.waypoints)
    ax.plot(xs, ys, "--", color="#555555", linewidth=1, label="path F")
    for i, (entry, track) in enumerate(zip(entries, tracks)):
        if track:
            tx, ty = zip(*track)
            ax.plot(tx, ty, color=TRACK_COLOURS[i % len(TRACK_COLOURS)], linewidth=1.1,
                    label="Test %d" % entry["test"])
    for kind, text in (("reached", "target, reached"), ("missed", "target, missed in a test"),
                       ("non_target", "non-target"), ("visited_non_target", "non-target, visited")):
        ax.plot([], [], "o", color=TREE_COLOURS[kind], alpha=0.5, label=text)
    save_map_figure(fig, ax, "%s: Tests %s" % (pmap.name.split(":")[0], ", ".join(str(e["test"]) for e in entries)),
                    path)
