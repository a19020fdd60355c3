"""Flight benchmark: what a flight costs, on the three paper maps. Prints figures, asserts nothing.

``foranav bench flight [--plant firmware] [--camera sim] [--json] [--seed N]``:

* oracle camera (default): simulated seconds flown per CPU second of the reduced plant's flights, and with
  ``--plant firmware`` the firmware plant's beside them, in one run;
* ``--camera sim``: each map flown with the vision camera (rendered frames, the camera module over the pty)
  and with the oracle on the same plant: CPU seconds of each (user + system, the camera's set-up included),
  their ratio, system time as a share of user time, and the vision flight's CPU by stage (render, module,
  wire, app, firmware, harness; ``host_tools.flight.stages``) plus its set-up (world and module loading).
"""
import argparse
import json
import resource
import sys
import time
from collections.abc import Callable

from host_tools.flight import OracleCamera, run_flight
from host_tools.flight.components import plant_config
from host_tools.flight.stages import STAGES
from host_tools.maps import load_map

MAPS = ("map1", "map2", "map3")


def _costed(fly: Callable[[], dict]) -> tuple[dict, dict]:
    """(summary, cost): user / system CPU seconds and wall seconds of ``fly()``."""
    before, wall0 = resource.getrusage(resource.RUSAGE_SELF), time.perf_counter()
    summary = fly()
    after = resource.getrusage(resource.RUSAGE_SELF)
    return summary, {"user_s": round(after.ru_utime - before.ru_utime, 3),
                     "system_s": round(after.ru_stime - before.ru_stime, 3),
                     "wall_s": round(time.perf_counter() - wall0, 2)}


def measure(seed: int = 0, plants: tuple[str, ...] = ("reduced",)) -> list[dict]:
    rows = []
    for plant in plants:
        for name in MAPS:
            pmap = load_map(name)
            summary, cost = _costed(lambda: run_flight(pmap, OracleCamera(pmap, seed=seed), seed=seed,
                                                       options={"plant": plant}))
            cpu = cost["user_s"] + cost["system_s"]
            rows.append({"plant": plant, "map": name, "mission_s": summary["mission_time_s"], "cpu_s": round(cpu, 2),
                         "wall_s": cost["wall_s"], "sim_s_per_cpu_s": round(summary["mission_time_s"] / max(cpu, 1e-6), 1)})
    return rows


def measure_vision(seed: int = 0, plant: str = "reduced") -> list[dict]:
    """Per map: the vision flight against the oracle flight of the same map and plant."""
    from host_tools.flight.vision_camera import VisionCamera  # the renderer loads only for this benchmark

    rows = []
    for name in MAPS:
        pmap = load_map(name)
        options = {"plant": plant, "profile": True}
        vision, vision_cost = _costed(lambda: run_flight(pmap, VisionCamera(pmap, seed=seed), seed=seed,
                                                         options=options))
        _, oracle_cost = _costed(lambda: run_flight(pmap, OracleCamera(pmap, seed=seed), seed=seed,
                                                    options={"plant": plant}))
        vision_cpu = vision_cost["user_s"] + vision_cost["system_s"]
        oracle_cpu = oracle_cost["user_s"] + oracle_cost["system_s"]
        stages = dict(vision["stage_cpu_s"])
        stages["setup"] = round(max(vision_cpu - sum(stages.values()), 0.0), 3)
        rows.append({"plant": plant, "map": name, "mission_s": vision["mission_time_s"],
                     "vision_cpu_s": round(vision_cpu, 2), "oracle_cpu_s": round(oracle_cpu, 2),
                     "ratio": round(vision_cpu / max(oracle_cpu, 1e-6), 2),
                     "vision_user_s": vision_cost["user_s"], "vision_system_s": vision_cost["system_s"],
                     "system_per_user": round(vision_cost["system_s"] / max(vision_cost["user_s"], 1e-6), 3),
                     "stages_cpu_s": stages})
    return rows


def _print_vision(rows: list[dict]) -> None:
    print("%-6s %11s %10s %10s %7s %9s %9s %8s" % ("map", "mission (s)", "vision CPU", "oracle CPU", "ratio",
                                                   "user (s)", "sys (s)", "sys/user"))
    for r in rows:
        print("%-6s %11.1f %10.2f %10.2f %7.2f %9.2f %9.2f %7.1f%%" % (
            r["map"], r["mission_s"], r["vision_cpu_s"], r["oracle_cpu_s"], r["ratio"], r["vision_user_s"],
            r["vision_system_s"], 100.0 * r["system_per_user"]))
    names = STAGES + ("setup",)
    print("\nvision flight CPU by stage (s):")
    print("%-6s " % "map" + " ".join("%9s" % n for n in names))
    for r in rows:
        print("%-6s " % r["map"] + " ".join("%9.2f" % r["stages_cpu_s"][n] for n in names))


def run(args: argparse.Namespace) -> int:
    plant = getattr(args, "plant", None) or "reduced"
    if plant != "reduced":
        plant_config(plant, None)  # built, or one line saying how
    seed = getattr(args, "seed", 0)
    if (getattr(args, "camera", None) or "oracle") == "sim":
        rows = measure_vision(seed, plant)
        if getattr(args, "json", False):
            print(json.dumps({"flight": rows}, indent=2))
        else:
            _print_vision(rows)
        return 0
    rows = measure(seed, ("reduced",) if plant == "reduced" else ("reduced", plant))
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
    parser.add_argument("--camera", choices=("oracle", "sim"), default="oracle")
    sys.exit(run(parser.parse_args()))
