"""The trajectory plot of a flight (matplotlib, Agg): map trees, path F, flown trajectory, detections."""
import os
from typing import Any

from crazyflie_app.app.navigation_core import PHASE_RECOVERY
from host_tools import fileio
from host_tools.flight.components import FlightView
from host_tools.maps import PlantationMap
from host_tools.plotting import Circle, PatchCollection, plt
from host_tools.sim.world import World

COLOURS = {"target": "#2e7d32", "non_target": "#9e9e9e", "reached": "#1565c0", "recovery": "#d32f2f",
           "path": "#555555", "truth": "#1565c0", "estimate": "#90caf9", "app_tree": "#ff8f00"}
# Tree ids are drawn up to this many trees: beyond, the labels overlap into a smudge and cost a text artist each
# (a 1000-tree map spent most of its plot time laying them out).
MAX_LABELLED_TREES = 200


def plot_trajectory(flight: FlightView, path: str | os.PathLike) -> None:
    """Draw ``flight`` (a harness Flight after its run) into the PNG ``path`` (atomic write)."""
    pmap = flight.pmap
    fig, ax = plt.subplots(figsize=(8, 3.6), dpi=110)
    world = getattr(flight.camera, "world", None)
    photos = world is not None and bool(world.photo_crowns)
    if photos:  # the map as the camera saw it: photo crowns under the track (outlined, not filled)
        show_mosaic(ax, world)
        zoom_to_content(ax, pmap)
    draw_trees(ax, pmap, {r["id"] for r in flight.reached}, photos)
    xs, ys = zip(*pmap.waypoints)
    ax.plot(xs, ys, "--", color=COLOURS["path"], linewidth=1, label="path F")
    if flight.trajectory:
        _, tx, ty, ex, ey, phases = zip(*flight.trajectory)
        ax.plot(ex, ey, color=COLOURS["estimate"], linewidth=0.8, label="estimate")
        ax.plot(tx, ty, color=COLOURS["truth"], linewidth=1.2, label="flown (truth)")
        recovery = [(x, y) for x, y, p in zip(tx, ty, phases) if p == PHASE_RECOVERY]
        if recovery:
            rx, ry = zip(*recovery)
            ax.plot(rx, ry, ".", color=COLOURS["recovery"], markersize=3, label="recovery")
    if flight.detections:
        dx, dy = zip(*flight.detections)
        ax.plot(dx, dy, ".", color=COLOURS["app_tree"], markersize=1.5, alpha=0.4, label="detections (app)")
    if flight.app_trees:
        _, ax_, ay_ = zip(*flight.app_trees)
        ax.plot(ax_, ay_, "x", color=COLOURS["app_tree"], markersize=5, label="trees stored by the app")
    killed_ms = getattr(flight, "camera_killed_ms", None)  # --realtime --kill-camera-at
    if killed_ms is not None and flight.trajectory:
        at = min(flight.trajectory, key=lambda row: abs(row[0] - killed_ms))
        ax.plot([at[1]], [at[2]], "*", color=COLOURS["recovery"], markersize=12, label="camera died")
        end = flight.trajectory[-1]
        ax.plot([end[1]], [end[2]], "v", color="black", markersize=7, label="landed")
    if flight.reached:
        px, py = zip(*(r["point"] for r in flight.reached))
        ax.plot(px, py, "+", color="black", markersize=9, label="declared reached")
    ax.plot([], [], "o", color=COLOURS["target"], alpha=0.4, label="target tree")
    ax.plot([], [], "o", color=COLOURS["non_target"], alpha=0.4, label="non-target tree")
    save_map_figure(fig, ax, pmap.name.split(":")[0] + " - seed %d" % flight.seed, path)


def draw_trees(ax: Any, pmap: PlantationMap, reached_ids: set, photos: bool) -> None:
    """The map's crowns as one collection (one artist, not one per tree), with their ids on small maps."""
    crowns = []
    for tree in pmap.trees:
        kind = "target" if tree.target else "non_target"
        crowns.append(Circle((tree.x, tree.y), tree.crown_m / 2, facecolor="none" if photos else COLOURS[kind],
                             alpha=0.8 if photos else 0.25,
                             edgecolor=COLOURS["reached"] if tree.id in reached_ids else COLOURS[kind],
                             linewidth=2.0 if tree.id in reached_ids else 1.0))
    if crowns:
        ax.add_collection(PatchCollection(crowns, match_original=True))
        ax.autoscale_view()
    if len(pmap.trees) <= MAX_LABELLED_TREES:
        for tree in pmap.trees:
            ax.annotate(str(tree.id), (tree.x, tree.y + tree.crown_m / 2 + 0.03), ha="center", fontsize=8)


def show_mosaic(ax: Any, world: World, level: int | None = None) -> None:
    """Draw a World's orthomosaic under a top-down plot (x right, y up, metres).

    Mosaic rows run along -x and columns along -y (host_tools/sim/world.py): transposed and mirrored for the plot.
    """
    level = len(world.levels) - 1 if level is None else level
    image = world.levels[level][..., ::-1]  # BGR -> RGB
    x_min, x_max, y_min, y_max = world.bounds
    ax.imshow(image.transpose(1, 0, 2)[:, ::-1], extent=(x_min, x_max, y_min, y_max), origin="upper",
              interpolation="bilinear", zorder=0)


def zoom_to_content(ax: Any, pmap: PlantationMap, margin_m: float = 0.4) -> None:
    """Limits around the path, trees and objects (the mosaic reaches a camera footprint beyond them)."""
    xs = [p[0] for p in pmap.waypoints] + [t.x for t in pmap.trees] + [o.x for o in pmap.objects]
    ys = [p[1] for p in pmap.waypoints] + [t.y for t in pmap.trees] + [o.y for o in pmap.objects]
    ax.set_xlim(min(xs) - margin_m, max(xs) + margin_m)
    ax.set_ylim(min(ys) - margin_m, max(ys) + margin_m)


def save_map_figure(fig: Any, ax: Any, title: str, path: str | os.PathLike) -> None:
    """Finish a top-down map plot (metres, equal axes, legend outside) and write it atomically."""
    ax.set_aspect("equal")
    ax.set_xlabel("x (m, forward)")
    ax.set_ylabel("y (m, left)")
    ax.set_title(title, fontsize=10)
    ax.grid(True, linewidth=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7)
    fig.tight_layout()
    fileio.write_figure(fig, path)
    plt.close(fig)
