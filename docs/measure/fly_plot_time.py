"""How long `foranav fly` spends drawing trajectory.png, on map1 and on map1 with 993 more (non-target) trees in a
40 x 25 m grid beside the path (1000 trees, the most a map may hold): docs/flight-app.md, "Outputs".

    .venv/bin/python docs/measure/fly_plot_time.py [OUT_DIR]

Prints, per map, the wall time of the whole command and of plot_trajectory alone (oracle camera, seed 0).
"""
import json
import sys
import time
from pathlib import Path

import host_tools.flight.plot as flight_plot
from host_tools import cli
from host_tools.maps import BUILTIN_DIR as MAPS_DIR

GRID_COLUMNS = 40


def thousand_tree_map(path: Path) -> Path:
    data = json.loads((MAPS_DIR / "map1.json").read_text())
    first = len(data["trees"])
    for i in range(1000 - first):
        data["trees"].append({"id": first + i + 1, "x": 10.0 + i % GRID_COLUMNS, "y": 5.0 + i // GRID_COLUMNS,
                              "species": "coconut", "crown_m": 0.35})
    data["name"] = "map1 + 993 trees"
    path.write_text(json.dumps(data))
    return path


def timed_fly(map_path: Path, out: Path) -> tuple[float, float]:
    draw, spent = flight_plot.plot_trajectory, []

    def timed(*args):
        start = time.perf_counter()
        draw(*args)
        spent.append(time.perf_counter() - start)

    flight_plot.plot_trajectory = timed
    try:
        start = time.perf_counter()
        code = cli.main(["fly", "--map", str(map_path), "--camera", "oracle", "--out", str(out), "--json"])
        total = time.perf_counter() - start
    finally:
        flight_plot.plot_trajectory = draw
    assert code == 0, code
    return total, spent[0]


def main() -> None:
    out = Path(sys.argv[1] if len(sys.argv) > 1 else "runs/fly-plot-time")
    out.mkdir(parents=True, exist_ok=True)
    maps = {"map1 (7 trees)": MAPS_DIR / "map1.json", "1000 trees": thousand_tree_map(out / "map1_1000.json")}
    rows = []
    for label, map_path in maps.items():
        total, plot = timed_fly(map_path, out / label.split()[0])
        rows.append("%-16s fly %.2f s, of which plot_trajectory %.2f s" % (label, total, plot))
    print("\n".join(rows))


if __name__ == "__main__":
    main()
