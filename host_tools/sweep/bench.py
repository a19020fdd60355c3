"""Sweep benchmark: flights per CPU-second and the speed-up from 1 to 2 Dask worker processes.

``foranav bench sweep [--camera sim|oracle] [--count N] [--json]``: the same N flights (sweep seed --seed,
no faults) on a LocalCluster of 1 worker, then of 2; each timed from the first submit to the last result,
after the workers have started and imported the flight code (one warm-up flight each, not counted).
Prints flights per second for each, the speed-up, and flights per CPU-second (CPU of the worker processes
while flying). The machine's load average is printed too: other work on the cores lowers the speed-up.
"""
import argparse
import json
import os
import time

from host_tools.sweep.runner import fly_on, open_client
from host_tools.sweep.specs import make_specs

DEFAULT_COUNT = 6
WORKER_COUNTS = (1, 2)


def _timed(workers, specs, warmup):
    client, cluster = open_client(workers=workers)
    try:
        client.wait_for_workers(workers)
        fly_on(client, warmup[:workers], lambda result: None, key_prefix="warmup")
        results = []
        wall0 = time.perf_counter()
        fly_on(client, specs, results.append, key_prefix="bench-%d" % workers)
        wall = time.perf_counter() - wall0
    finally:
        client.close()
        cluster.close()
    cpu = sum(r.get("cpu_s") or 0.0 for r in results)
    ok = sum(1 for r in results if r["status"] == "ok")
    return {"workers": workers, "flights": len(results), "ok": ok, "wall_s": round(wall, 2),
            "flights_per_s": round(len(results) / wall, 4), "cpu_s": round(cpu, 2),
            "flights_per_cpu_s": round(len(results) / cpu, 4) if cpu else None}


def measure(camera: str = "sim", count: int = DEFAULT_COUNT, seed: int = 0) -> dict:
    specs = make_specs(count, seed, camera=camera)
    warmup = [dict(s, index=10 ** 6 + s["index"]) for s in make_specs(2, seed + 1, camera=camera)]
    load0 = os.getloadavg()[0]
    rows = [_timed(w, specs, warmup) for w in WORKER_COUNTS]
    return {"camera": camera, "count": count, "rows": rows,
            "speedup_1_to_2": round(rows[1]["flights_per_s"] / rows[0]["flights_per_s"], 3),
            "cpus": os.cpu_count(), "load_average_before": round(load0, 2),
            "load_average_after": round(os.getloadavg()[0], 2)}


def run(args: argparse.Namespace) -> int:
    result = measure(getattr(args, "camera", None) or "sim", getattr(args, "count", None) or DEFAULT_COUNT,
                     getattr(args, "seed", 0))
    if getattr(args, "json", False):
        print(json.dumps({"sweep": result}, indent=2))
        return 0
    print("%d %s flights (no faults), %d CPUs, load average %.2f -> %.2f" % (
        result["count"], result["camera"], result["cpus"], result["load_average_before"],
        result["load_average_after"]))
    print("%-8s %8s %10s %12s %10s %16s" % ("workers", "flights", "wall (s)", "flights/s", "CPU (s)",
                                            "flights/CPU-s"))
    for r in result["rows"]:
        print("%-8d %8d %10.2f %12.4f %10.2f %16.4f" % (r["workers"], r["flights"], r["wall_s"], r["flights_per_s"],
                                                      r["cpu_s"], r["flights_per_cpu_s"] or 0.0))
    print("speed-up 1 -> 2 workers: %.2fx" % result["speedup_1_to_2"])
    return 0
