"""The sweep report: flawless rate with a 95 % Wilson interval, failure taxonomy, deviation distribution,
rates by factor, the worst flights with the fly command that replays each, and every failed flight with the
plantation and fly commands that replay it.

    build_report(rows, out_dir) -> report dict;  write_report(report, rows, out_dir) -> report.md + PNGs

A flight is flawless when the harness calls it a success: every target reached exactly once, no non-target
visited, nothing "reached" where there is no tree, no watchdog event, mission completed. Failure classes
(a flight can be in several): crash (the flight raised: traceback stored), not completed, missed target,
repeated target, non-target visited, reached nothing (a reach 0.3 m from every tree), watchdog.
"""
import math
import os
from collections.abc import Sequence
from pathlib import Path

from host_tools import fileio
from host_tools.plantation_ranges import PlantationRanges
from host_tools.plotting import plt
from host_tools.sweep.specs import fly_command, plantation_command, seed_role

Z95 = 1.959964
WORST_SHOWN = 10
FAILURE_CLASSES = ("crash", "not completed", "missed target", "repeated target", "non-target visited",
                   "reached nothing", "watchdog")
# factor -> (where it lives, bin edges or None for categories)
FACTORS = {
    "altitude_m": ("factors", (0.9, 1.0, 1.125, 1.25, 1.375, 1.5001)),
    "columns": ("factors", None),
    "column_length_m": ("factors", (1.2, 2.4, 3.6, 5.0001)),
    "column_spacing_m": ("factors", (0.9, 1.2, 2.0, 3.0, 5.0001)),
    "tree_spacing_m": ("factors", (0.45, 0.52, 0.59, 0.65, 0.9001)),
    "lateral_jitter_m": ("factors", (0.0, 0.04, 0.08, 0.1201)),
    "heading_deg": ("factors", (0.0, 45.0, 90.0, 135.0, 180.0, 225.0, 270.0, 315.0, 360.0)),
    "bends": ("factors", None),
    "column_offset_m": ("factors", (0.0, 0.2, 0.4, 0.6001)),
    "column_end_margin_m": ("factors", (0.15, 0.25, 0.35, 0.4501)),
    "crown_px_max": ("factors", (0.0, 120.0, 140.0, 161.0, 200.0)),
    "clusters": ("factors", "any"),
    "gaps": ("factors", "any"),
    "lookalikes_in_column": ("factors", "any"),
    "lookalikes_beside": ("factors", "any"),
    "off_column_palms": ("factors", "any"),
    "roofs": ("factors", "any"),
    "road_crossings": ("factors", "any"),
    "dropout": ("conditions", (0.0, 0.1, 0.2, 0.3, 0.4001)),
    "pixel_noise_px": ("conditions", (0.0, 1.0, 2.0, 3.0, 4.0001)),
    "frame_period_ms": ("conditions", (90, 125, 167, 251)),
    "latency_ms": ("conditions", (0, 150, 300, 750)),
    "wind_mps2": ("conditions", (0.0, 0.2, 0.4, 0.8001)),
    "estimator": ("conditions", None),
    "cam_offset_m": ("conditions", (0.0, 0.04, 0.08, 0.1501)),
    "flow_scale": ("conditions", (0.9, 0.95, 1.0, 1.05, 1.1001)),
    "flow_bias_counts": ("conditions", (0.0, 0.025, 0.05, 0.075, 0.1001)),
    "ground_texture": ("conditions", (0.0, 0.35, 0.5, 0.75, 1.0001)),
    # what a user can measure of their own deck: the largest position error of the estimate over the flight,
    # per 10 m flown (m)
    "drift_per_10m_m": ("summary", (0.0, 0.25, 0.5, 1.0, 2.0, 4.0)),
}


def wilson(successes: int, n: int, z: float = Z95) -> tuple[float, float]:
    """Wilson score interval (lo, hi) of a binomial proportion; (None, None) for n = 0."""
    if n == 0:
        return None, None
    p = successes / n
    denom = 1 + z * z / n
    centre = (p + z * z / (2 * n)) / denom
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / denom
    return max(0.0, centre - half), min(1.0, centre + half)


def failure_classes(row: dict) -> list[str]:
    """The failure classes of one stored flight (empty for a flawless one)."""
    if row["status"] != "ok":
        return ["crash"]
    s = row["summary"]
    out = []
    if not s["completed"]:
        out.append("not completed")
    if s["missed_targets"]:
        out.append("missed target")
    if s["repeated_targets"]:
        out.append("repeated target")
    if s["non_targets_visited"]:
        out.append("non-target visited")
    if s["spurious_reached"]:
        out.append("reached nothing")
    if s["watchdog_events"]:
        out.append("watchdog")
    if not out and not s["success"]:
        out.append("not completed")
    return out


def flawless(row: dict) -> bool:
    return row["status"] == "ok" and bool(row["summary"]["success"])


def drift_per_10m(summary: dict | None) -> float | None:
    """The estimate's largest position error over the flight per 10 m flown (m), or None (no figures)."""
    error, flown = (summary or {}).get("estimate_error"), (summary or {}).get("flown_m")
    if not error or not flown:
        return None
    return error["position_m"]["max"] / flown * 10.0


def _factor_value(row, name):
    where, _ = FACTORS[name]
    if where == "summary":
        return drift_per_10m(row.get("summary")) if row["status"] == "ok" else None
    source = row["spec"][where]
    if name == "cam_offset_m":
        value = source.get(name)
        return None if value is None else math.hypot(*value)
    return source.get(name)


def _bin_label(value, edges):
    if edges is None:
        return str(value)
    if edges == "any":
        return "0" if not value else ">= 1"
    for lo, hi in zip(edges[:-1], edges[1:]):
        if lo <= value < hi:
            return "%g-%g" % (lo, round(hi, 3))
    return ">= %g" % edges[-1] if value >= edges[-1] else "< %g" % edges[0]


def rates_by_factor(rows: Sequence[dict]) -> dict[str, list[dict]]:
    """{factor: [{bin, flights, flawless, rate, lo, hi}]} for every factor that varies in ``rows``."""
    out = {}
    for name, (_, edges) in FACTORS.items():
        groups = {}
        for row in rows:
            value = _factor_value(row, name)
            if value is None:
                continue
            groups.setdefault(_bin_label(value, edges), []).append(flawless(row))
        if len(groups) < 2:
            continue
        table = []
        for label in sorted(groups, key=_sort_key):
            ok = groups[label]
            lo, hi = wilson(sum(ok), len(ok))
            table.append({"bin": label, "flights": len(ok), "flawless": sum(ok),
                          "rate": round(sum(ok) / len(ok), 4), "lo": round(lo, 4), "hi": round(hi, 4)})
        out[name] = table
    return out


def _sort_key(label):
    head = label.replace(">= ", "").replace("< ", "").split("-")[0]
    try:
        return (0, float(head))
    except ValueError:
        return (1, label)


def _quantiles(values, qs=(0.5, 0.9, 0.95, 0.99)):
    if not values:
        return {}
    ordered = sorted(values)
    out = {}
    for q in qs:
        pos = q * (len(ordered) - 1)
        lo, hi = int(math.floor(pos)), int(math.ceil(pos))
        out["p%d" % round(q * 100)] = round(ordered[lo] + (ordered[hi] - ordered[lo]) * (pos - lo), 4)
    return out


def _badness(row):
    """Sort key of the worst flights: crashes, then failures by number of classes, then max deviation."""
    classes = failure_classes(row)
    s = row["summary"] or {}
    return (row["status"] != "ok", len(classes), s.get("max_deviation_m") or 0.0)


def build_report(rows: Sequence[dict], out_dir: str | os.PathLike, identity: dict | None = None,
                 ranges: PlantationRanges | None = None) -> dict:
    out_dir = Path(out_dir)
    n = len(rows)
    ok = sum(1 for r in rows if flawless(r))
    lo, hi = wilson(ok, n)
    taxonomy = {name: 0 for name in FAILURE_CLASSES}
    for row in rows:
        for name in failure_classes(row):
            taxonomy[name] += 1
    deviations = [reach["deviation_m"] for r in rows if r["status"] == "ok"
                  for reach in r["summary"]["reached"] if reach["id"] in set(r["summary"]["targets"])]
    flight_means = [r["summary"]["mean_deviation_m"] for r in rows
                    if r["status"] == "ok" and r["summary"]["mean_deviation_m"] is not None]
    cpu = [r["cpu_s"] for r in rows if r.get("cpu_s")]
    worst = sorted((r for r in rows if not flawless(r)), key=_badness, reverse=True)[:WORST_SHOWN]
    if len(worst) < WORST_SHOWN:  # fill with the flawless flights of largest deviation
        rest = sorted((r for r in rows if flawless(r)), key=lambda r: r["summary"]["max_deviation_m"] or 0.0,
                      reverse=True)
        worst += rest[:WORST_SHOWN - len(worst)]
    worst_rows = []
    for row in worst:
        map_path = out_dir / "maps" / ("flight-%05d.json" % row["index"])
        s = row["summary"] or {}
        worst_rows.append({
            "index": row["index"], "seed": row["spec"]["seed"], "plantation_seed": row["spec"]["plantation_seed"],
            "flawless": flawless(row), "failures": failure_classes(row),
            "missed": s.get("missed_targets"), "repeated": s.get("repeated_targets"),
            "non_targets": s.get("non_targets_visited"), "max_deviation_m": s.get("max_deviation_m"),
            "altitude_m": row["spec"]["factors"]["altitude_m"], "conditions": row["spec"]["conditions"],
            "map": str(map_path), "fly": fly_command(row["spec"], map_path),
            "plantation": plantation_command(row["spec"], map_path, ranges),
            "error": (row["traceback"] or "").strip().splitlines()[-1] if row["status"] != "ok" else None})
    return {
        "sweep": identity or {},
        "flights": n,
        "flawless": ok,
        "flawless_rate": round(ok / n, 4) if n else None,
        "wilson95": [None if lo is None else round(lo, 4), None if hi is None else round(hi, 4)],
        "failures": taxonomy,
        "deviation_m": {"reaches": len(deviations),
                        "mean": round(sum(deviations) / len(deviations), 4) if deviations else None,
                        "max": max(deviations) if deviations else None, **_quantiles(deviations)},
        "mean_of_flight_means_m": round(sum(flight_means) / len(flight_means), 4) if flight_means else None,
        "cpu_s_per_flight": round(sum(cpu) / len(cpu), 2) if cpu else None,
        "rates_by_factor": rates_by_factor(rows),
        "worst": worst_rows,
        "failed": [_failed_row(row, out_dir, ranges) for row in rows if not flawless(row)],
    }


def _failed_row(row: dict, out_dir: Path, ranges: PlantationRanges | None) -> dict:
    """A failed flight, with the two commands that replay it (the plantation command writes its map)."""
    map_path = out_dir / "maps" / ("flight-%05d.json" % row["index"])
    return {"index": row["index"], "failures": failure_classes(row), "conditions": row["spec"]["conditions"],
            "plantation": plantation_command(row["spec"], map_path, ranges),
            "fly": fly_command(row["spec"], map_path)}


def write_report(report: dict, rows: Sequence[dict], out_dir: str | os.PathLike) -> None:
    """report.md, deviations.png, rates.png and the worst flights' maps under out_dir/maps/."""
    out_dir = Path(out_dir)
    by_index = {r["index"]: r for r in rows}
    for w in report["worst"]:
        fileio.write_json(w["map"], by_index[w["index"]]["spec"]["map"])
    _plot_deviations(rows, out_dir / "deviations.png")
    _plot_rates(report, out_dir / "rates.png")
    fileio.write_text(out_dir / "report.md", markdown(report))


def headline(report: dict) -> str:
    """The headline table (markdown) of a report."""
    lo, hi = report["wilson95"]
    dev = report["deviation_m"]
    sweep = report["sweep"]
    lines = ["| flights | camera | faults | flawless | rate | 95 % Wilson | mean deviation (m) | p95 (m) | max (m) |",
             "|---|---|---|---|---|---|---|---|---|",
             "| %d | %s | %s | %d | %s | %s | %s | %s | %s |" % (
                 report["flights"], sweep.get("camera", "?"), sweep.get("faults", "?"), report["flawless"],
                 _pct(report["flawless_rate"]), "-" if lo is None else "%s - %s" % (_pct(lo), _pct(hi)),
                 _num(dev.get("mean")), _num(dev.get("p95")), _num(dev.get("max")))]
    return "\n".join(lines)


def _pct(x):
    return "-" if x is None else "%.1f %%" % (100 * x)


def _num(x):
    return "-" if x is None else "%.3f" % x


def markdown(report: dict) -> str:
    out = ["# Sweep report", ""]
    sweep = report["sweep"]
    if sweep:
        out += ["Sweep: " + ", ".join("%s %s" % (k, v) for k, v in sorted(sweep.items())), ""]
    if "seed" in sweep:
        out += ["Seed %s is a %s seed (docs/sweeps.md: only reporting seeds give reported rates)."
                % (sweep["seed"], seed_role(int(sweep["seed"]))), ""]
    out += [headline(report), ""]
    out += ["Mean of the per-flight mean deviations: %s m; CPU per flight: %s s." % (
        _num(report["mean_of_flight_means_m"]), report["cpu_s_per_flight"]), ""]
    out += ["## Failure taxonomy", "", "| class | flights |", "|---|---|"]
    out += ["| %s | %d |" % (name, count) for name, count in report["failures"].items()]
    dev = report["deviation_m"]
    out += ["", "## Deviation at each target reached", "",
            "%d reaches: mean %s m, median %s, p90 %s, p95 %s, p99 %s, max %s (deviations.png)." % (
                dev["reaches"], _num(dev.get("mean")), _num(dev.get("p50")), _num(dev.get("p90")),
                _num(dev.get("p95")), _num(dev.get("p99")), _num(dev.get("max"))),
            "", "![deviations](deviations.png)", "", "## Flawless rate by factor", "", "![rates](rates.png)", ""]
    for name, table in report["rates_by_factor"].items():
        out += ["**%s**" % name, "", "| bin | flights | flawless | rate (95 % Wilson) |", "|---|---|---|---|"]
        out += ["| %s | %d | %d | %s (%s - %s) |" % (r["bin"], r["flights"], r["flawless"], _pct(r["rate"]),
                                                     _pct(r["lo"]), _pct(r["hi"])) for r in table]
        out.append("")
    out += ["## Worst flights", "", "Each replays with its fly command (the map is written next to this "
            "report; the plantation command writes it again).", ""]
    for w in report["worst"]:
        what = "flawless" if w["flawless"] else ", ".join(w["failures"])
        detail = []
        if w["missed"]:
            detail.append("missed %s" % w["missed"])
        if w["repeated"]:
            detail.append("repeated %s" % w["repeated"])
        if w["non_targets"]:
            detail.append("non-targets %s" % w["non_targets"])
        if w["error"]:
            detail.append(w["error"])
        out += ["- flight %d (%s%s; max deviation %s m, altitude %.2f m)" % (
            w["index"], what, "; " + "; ".join(detail) if detail else "", _num(w["max_deviation_m"]),
            w["altitude_m"]), "", "      %s" % w["fly"], "      %s" % w["plantation"], ""]
    if report["failed"]:
        out += ["## Every failed flight", "", "By index; the plantation command writes the map the fly command "
                "replays.", ""]
        for f in report["failed"]:
            conditions = ", ".join("%s %s" % (k, v) for k, v in sorted(f["conditions"].items())
                                   if k in ("estimator", "wind_mps2"))
            out += ["- flight %d (%s%s)" % (f["index"], ", ".join(f["failures"]) or "raised",
                                           "; " + conditions if conditions else ""),
                    "", "      %s" % f["plantation"], "      %s" % f["fly"], ""]
    return "\n".join(out) + "\n"


def _plot_deviations(rows, path):
    deviations = [reach["deviation_m"] for r in rows if r["status"] == "ok"
                  for reach in r["summary"]["reached"] if reach["id"] in set(r["summary"]["targets"])]
    fig, ax = plt.subplots(figsize=(6, 3.2), dpi=110)
    if deviations:
        ax.hist(deviations, bins=40, color="#1565c0", alpha=0.8)
        ax.axvline(0.05, color="#d32f2f", linewidth=1, label="0.05 m")
        ax.legend(fontsize=8)
    ax.set_xlabel("deviation at the reached target (m)")
    ax.set_ylabel("reaches")
    ax.set_title("Deviation distribution (%d reaches, %d flights)" % (len(deviations), len(rows)), fontsize=10)
    fig.tight_layout()
    fileio.write_figure(fig, path)
    plt.close(fig)


def _plot_rates(report, path):
    tables = report["rates_by_factor"]
    n = max(len(tables), 1)
    cols = 3
    rows_ = int(math.ceil(n / cols))
    fig, axes = plt.subplots(rows_, cols, figsize=(10, 2.4 * rows_), dpi=100, squeeze=False)
    for ax, (name, table) in zip(axes.flat, tables.items()):
        x = range(len(table))
        rates = [100 * r["rate"] for r in table]
        err = [[100 * (r["rate"] - r["lo"]) for r in table], [100 * (r["hi"] - r["rate"]) for r in table]]
        ax.bar(x, rates, yerr=err, color="#2e7d32", alpha=0.75, capsize=2)
        ax.set_xticks(list(x))
        ax.set_xticklabels([r["bin"] for r in table], fontsize=7)
        ax.set_ylim(max(0.0, min([90.0] + [100 * r["lo"] - 2 for r in table])), 100.5)
        ax.set_title(name, fontsize=9)
        ax.tick_params(axis="y", labelsize=7)
    for ax in list(axes.flat)[len(tables):]:
        ax.axis("off")
    fig.suptitle("Flawless rate (%) by factor, 95 % Wilson intervals", fontsize=10)
    fig.tight_layout()
    fileio.write_figure(fig, path)
    plt.close(fig)
