"""Flight benchmark: simulated seconds flown per CPU second, oracle camera, the three paper maps.

Meant for ``foranav bench flight [--plant firmware] [--json] [--seed N]`` (the bench dispatcher lists its
targets): the reduced plant's flights, and with ``--plant firmware`` the firmware plant's beside them, in one
run. Prints figures, asserts nothing.
"""
import argparse
import json
import sys
import time

from host_tools.flight import OracleCamera, run_flight
from host_tools.flight.components import plant_config
from host_tools.maps import load_map

MAPS = ("map1", "map2", "map3")


def measure(seed: int = 0, plants: tuple[str, ...] = ("reduced",)) -> list[dict]:
    rows = []
    for plant in plants:
        for name in MAPS:
            pmap = load_map(name)
            wall0 = time.perf_counter()
            summary = run_flight(pmap, OracleCamera(pmap, seed=seed), seed=seed, options={"plant": plant})
            wall = time.perf_counter() - wall0
            rows.append({"plant": plant, "map": name, "mission_s": summary["mission_time_s"],
                         "cpu_s": summary["cpu_s"], "wall_s": round(wall, 2),
                         "sim_s_per_cpu_s": round(summary["mission_time_s"] / max(summary["cpu_s"], 1e-6), 1)})
    return rows


def run(args: argparse.Namespace) -> int:
    plant = getattr(args, "plant", None) or "reduced"
    plants = ("reduced",) if plant == "reduced" else ("reduced", plant)
    if plant != "reduced":
        plant_config(plant, None)  # built, or one line saying how
    rows = measure(getattr(args, "seed", 0), plants)
    if getattr(args, "json", False):
        print(json.dumps({"flight": rows}, indent=2))
    else:
        print("%-9s %-6s %12s %10s %10s %16s" % ("plant", "map", "mission (s)", "CPU (s)", "wall (s)", "sim s / CPU s"))
        for r in rows:
            print("%-9s %-6s %12.1f %10.2f %10.2f %16.1f" % (r["plant"], r["map"], r["mission_s"], r["cpu_s"],
                                                             r["wall_s"], r["sim_s_per_cpu_s"]))
    return 0


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--seed", type=int, default=0)
    sys.exit(run(parser.parse_args()))
