"""Scoring of a finished flight: the summary record ``foranav fly`` prints and the sweeps store."""
import math
from pathlib import Path

from crazyflie_app.firmware.supervisor import LOCKED
from crazyflie_app.app.navigation_core import PHASE_DONE, PHASE_NO_CAMERA
from host_tools.flight.components import FlightView
from host_tools.flight.stats import mean_ci95


def _figures(values: list[float], digits: int) -> dict:
    ordered = sorted(values)
    p95 = ordered[min(len(ordered) - 1, int(math.ceil(0.95 * len(ordered))) - 1)]
    return {"mean": round(sum(ordered) / len(ordered), digits), "p95": round(p95, digits),
            "max": round(ordered[-1], digits)}


def error_figures(errors: list[tuple[float, float]]) -> dict | None:
    """mean / p95 / max of the state estimate's position (m) and yaw (deg) errors while airborne."""
    if not errors:
        return None
    return {"position_m": _figures([e[0] for e in errors], 4), "yaw_deg": _figures([e[1] for e in errors], 2)}


def flown_m(record) -> float:
    """The true horizontal distance flown while airborne (m, from the trajectory samples): what an estimate's
    drift per distance is taken over."""
    end = record.done_ms if record.done_ms is not None else float("inf")
    points = [(x, y) for t, x, y, _, _, _ in record.trajectory
              if record.takeoff_ms is not None and record.takeoff_ms <= t <= end]
    return round(sum(math.hypot(b[0] - a[0], b[1] - a[1]) for a, b in zip(points, points[1:])), 3)


def summarize(flight: FlightView) -> dict:
    """The flight summary (the record fly prints and sweeps store) of a finished Flight."""
    rig, record, pmap = flight.rig, flight.record, flight.pmap
    targets = sorted(t.id for t in pmap.targets)
    target_set = set(targets)
    visits = [r["id"] for r in record.reached]
    non_targets = [i for i in visits if i is not None and i not in target_set]
    deviations = [r["deviation_m"] for r in record.reached if r["id"] in target_set]
    mean, ci95 = mean_ci95(deviations)
    supervisor, app = rig.cf.supervisor, rig.app
    watchdog = [{"t_s": t / 1000.0, "state": s} for t, s in supervisor.watchdog_events]
    # a landing forced by a dead camera link is safe, but the mission was not completed; nor is a mission over
    # targets whose camera reported no tree at all (a model that cannot run, a covered lens): it flew blind
    blind = bool(targets) and app.core.counters.detections == 0
    completed = (app.phase == PHASE_DONE and supervisor.state != LOCKED and not app.core.link_aborted
                 and not rig.cf.model.crashed and not blind)
    counts = {i: visits.count(i) for i in targets}
    success = (completed and all(c == 1 for c in counts.values()) and not non_targets
               and None not in visits and not watchdog)
    end_ms = record.done_ms if record.done_ms is not None else rig.now()
    counters = app.core.counters
    return {
        "map": Path(pmap.source).stem if pmap.source else pmap.name,
        "seed": flight.seed,
        "completed": completed,
        "success": success,
        "targets": targets,
        "reached": [{"id": r["id"], "deviation_m": r["deviation_m"], "t_s": r["t_s"]} for r in record.reached],
        "missed_targets": [i for i in targets if counts[i] == 0],
        "repeated_targets": [i for i in targets if counts[i] > 1],
        "non_targets_visited": non_targets,
        "spurious_reached": sum(1 for i in visits if i is None),
        "mean_deviation_m": None if mean is None else round(mean, 4),
        "ci95_m": None if ci95 is None else round(ci95, 4),
        "max_deviation_m": max(deviations) if deviations else None,
        "mission_time_s": round((end_ms - (record.takeoff_ms or 0)) / 1000.0, 2),
        "recoveries": counters.recoveries,
        "abandoned": counters.abandoned,
        "watchdog_events": len(watchdog),
        "watchdog": watchdog,
        "detections": counters.detections,
        "out_of_column_detections": counters.out_of_column,
        "serial_lines_dropped": app.link.lines_dropped,
        "link_losses": counters.link_losses,
        "link_aborted": app.core.link_aborted,
        "camera_never_heard": app.phase == PHASE_NO_CAMERA,  # did not take off: not completed
        "camera_blind": blind and app.phase != PHASE_NO_CAMERA,  # flew, but saw no tree: not completed
        "plant": flight.options["plant"],
        "crashed": rig.cf.model.crashed,
        "crash": rig.cf.model.crash_reason,
        "estimate_error": error_figures(record.estimate_errors),
        "flown_m": flown_m(record),
        "hidden_tree": flight.options["hide_tree"],
        "hidden_from_s": None if flight.hide.started_ms is None else flight.hide.started_ms / 1000.0,
    }
