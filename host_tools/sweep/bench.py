"""Sweep benchmark: what a sweep's flights cost and how they scale from 1 to 2 Dask worker processes.

``foranav bench sweep [--camera sim|oracle] [--count N] [--plant P] [--json]``: the same N flights (sweep seed
--seed, no faults) on a LocalCluster of 1 worker, then of 2; each timed from the first submit to the last
result, after the workers have started and imported the flight code (one warm-up flight each, not counted).
Prints flights per second for each, the speed-up, CPU per flight (user and system) and the largest worker
memory; with the vision camera also the same flights with the oracle (on 2 workers), the vision / oracle CPU
ratio, the vision flights' CPU by stage (``host_tools.flight.stages``), and what 1,000 vision flights take on
2 workers at the measured rate. The machine's load average is printed too: other work on the cores lowers
the speed-up.
"""
import argparse
import json
import os
import time

from host_tools.flight.stages import STAGES
from host_tools.sweep.runner import close_client, fly_on, open_client
from host_tools.sweep.specs import make_specs

DEFAULT_COUNT = 6
WORKER_COUNTS = (1, 2)
PROJECTED_FLIGHTS = 1000


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
        close_client(client, cluster)
    return _row(workers, results, wall)


def _mean(results, key):
    values = [r[key] for r in results if r.get(key) is not None]
    return round(sum(values) / len(values), 3) if values else None


def _row(workers, results, wall):
    cpu = sum(r.get("cpu_s") or 0.0 for r in results)
    ok = sum(1 for r in results if r["status"] == "ok")
    row = {"workers": workers, "flights": len(results), "ok": ok, "wall_s": round(wall, 2),
           "flights_per_s": round(len(results) / wall, 4), "cpu_s": round(cpu, 2),
           "flights_per_cpu_s": round(len(results) / cpu, 4) if cpu else None,
           "user_s_per_flight": _mean(results, "user_s"), "system_s_per_flight": _mean(results, "system_s"),
           "max_worker_rss_mb": max((r.get("max_rss_mb") or 0.0 for r in results), default=None)}
    staged = [r["stage_cpu_s"] for r in results if r.get("stage_cpu_s")]
    if staged:
        row["stage_cpu_s_per_flight"] = {s: round(sum(x[s] for x in staged) / len(staged), 3) for s in STAGES}
    return row


def _profiled(specs):
    return [dict(s, profile=True) for s in specs]


def measure(camera: str = "sim", count: int = DEFAULT_COUNT, seed: int = 0, plant: str = "reduced") -> dict:
    fly_args = ["--plant", plant] if plant != "reduced" else []
    specs = _profiled(make_specs(count, seed, camera=camera, fly_args=fly_args))
    warmup = [dict(s, index=10 ** 6 + s["index"]) for s in make_specs(2, seed + 1, camera=camera, fly_args=fly_args)]
    load0 = os.getloadavg()[0]
    rows = [_timed(w, specs, warmup) for w in WORKER_COUNTS]
    result = {"camera": camera, "plant": plant, "count": count, "rows": rows,
              "speedup_1_to_2": round(rows[1]["flights_per_s"] / rows[0]["flights_per_s"], 3),
              "cpus": os.cpu_count()}
    if camera == "sim":
        oracle_specs = make_specs(count, seed, camera="oracle", fly_args=fly_args)
        oracle_warmup = make_specs(2, seed + 1, camera="oracle", fly_args=fly_args)
        oracle = _timed(WORKER_COUNTS[-1], oracle_specs, [dict(s, index=10 ** 6 + s["index"]) for s in oracle_warmup])
        result["oracle"] = oracle
        vision_cpu = rows[-1]["cpu_s"] / max(rows[-1]["flights"], 1)
        oracle_cpu = oracle["cpu_s"] / max(oracle["flights"], 1)
        result["vision_to_oracle_cpu"] = round(vision_cpu / max(oracle_cpu, 1e-9), 2)
        result["projected_1000_flights_min_2_workers"] = round(PROJECTED_FLIGHTS / rows[-1]["flights_per_s"] / 60, 1)
    result["load_average_before"] = round(load0, 2)
    result["load_average_after"] = round(os.getloadavg()[0], 2)
    return result


def _print(result: dict) -> None:
    print("%d %s flights (no faults, %s plant), %d CPUs, load average %.2f -> %.2f" % (
        result["count"], result["camera"], result["plant"], result["cpus"], result["load_average_before"],
        result["load_average_after"]))
    print("%-14s %8s %10s %12s %10s %12s %12s %10s" % ("flights", "workers", "wall (s)", "flights/s", "CPU (s)",
                                                       "user/flight", "sys/flight", "RSS (MB)"))
    labelled = [(result["camera"], r) for r in result["rows"]]
    if "oracle" in result:
        labelled.append(("oracle", result["oracle"]))
    for label, r in labelled:
        print("%-14s %8d %10.2f %12.4f %10.2f %12.3f %12.3f %10.0f" % (
            label, r["workers"], r["wall_s"], r["flights_per_s"], r["cpu_s"], r["user_s_per_flight"] or 0.0,
            r["system_s_per_flight"] or 0.0, r["max_worker_rss_mb"] or 0.0))
    print("speed-up 1 -> 2 workers: %.2fx" % result["speedup_1_to_2"])
    if "oracle" in result:
        print("CPU per vision flight / per oracle flight: %.2fx" % result["vision_to_oracle_cpu"])
        print("1,000 vision flights on 2 workers at this rate: %.1f min" % result["projected_1000_flights_min_2_workers"])
    stages = result["rows"][-1].get("stage_cpu_s_per_flight")
    if stages:
        print("CPU per %s flight by stage (s): %s" % (result["camera"], ", ".join(
            "%s %.2f" % (name, stages[name]) for name in STAGES)))


def run(args: argparse.Namespace) -> int:
    result = measure(getattr(args, "camera", None) or "sim", getattr(args, "count", None) or DEFAULT_COUNT,
                     getattr(args, "seed", 0), getattr(args, "plant", None) or "reduced")
    if getattr(args, "json", False):
        print(json.dumps({"sweep": result}, indent=2))
        return 0
    _print(result)
    return 0
