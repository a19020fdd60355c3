"""Sweep specs, conditions, the replay command, the store and the report's statistics (no cluster here)."""
import json
import subprocess
import sys

import pytest

from host_tools import fileio
from host_tools.errors import ForaNavError
from host_tools.sweep import conditions as cond
from host_tools.sweep.report import build_report, failure_classes, markdown, wilson
from host_tools.sweep.runner import fly_task
from host_tools.sweep.specs import (TUNING_PLANTATION_SEEDS, flight_spec, fly_command, make_specs, plantation_seed,
                                    seed_role)
from host_tools.sweep.store import SweepStore
from host_tools.plantation_ranges import PlantationRanges

SMALL = PlantationRanges(columns=(1, 1), column_length_m=(1.5, 1.8))  # quick oracle flights
OUTPUT_KEYS = {"map", "tlog", "plot", "summary", "detections_csv", "cpu_s"}  # paths, names and timing


def test_that_the_same_seed_gives_the_same_specs_whatever_the_count():
    # Test
    short = make_specs(3, 7, faults="moderate", camera="oracle")
    long = make_specs(5, 7, faults="moderate", camera="oracle")
    other = make_specs(3, 8, faults="moderate", camera="oracle")
    # Assert
    assert json.dumps(short) == json.dumps(long[:3])
    assert [s["map"] for s in short] != [s["map"] for s in other]
    assert len({s["seed"] for s in long}) == 5


def test_that_reporting_sweeps_fly_no_plantation_of_the_tuning_seeds():
    # docs/sweeps.md: tuning sweep seeds 0-999 and plantation seeds below 10,000; reporting sweeps 1000-1999
    assert (seed_role(1), seed_role(999), seed_role(1000), seed_role(1999), seed_role(2000)) == \
        ("tuning", "tuning", "reporting", "reporting", "unassigned")
    assert flight_spec(1001, 3, camera="oracle")["plantation_seed"] == plantation_seed(1001, 3)
    tuning = {plantation_seed(seed, i) for seed in range(50) for i in range(500)}
    reporting = {plantation_seed(seed, i) for seed in range(1000, 1010) for i in range(2000)}
    assert not reporting & tuning
    assert not any(seed in TUNING_PLANTATION_SEEDS for seed in reporting)


@pytest.mark.parametrize("faults", sorted(cond.FAULT_PRESETS))
def test_that_each_preset_draws_within_its_stated_ranges(faults):
    import numpy as np
    spec = cond.preset(faults)
    for i in range(200):
        drawn = cond.draw(np.random.default_rng(i), spec, "sim")
        if faults == "none":
            assert drawn == {}
            continue
        assert spec["dropout"][0] <= drawn["dropout"] <= spec["dropout"][1]
        assert spec["pixel_noise_px"][0] <= drawn["pixel_noise_px"] <= spec["pixel_noise_px"][1]
        fps = 1000.0 / drawn["frame_period_ms"]
        assert spec["fps"][0] - 0.1 <= fps <= spec["fps"][1] + 0.1
        frames = drawn["latency_ms"] / drawn["frame_period_ms"]
        assert spec["latency_frames"][0] - 0.01 <= frames <= spec["latency_frames"][1] + 0.01
        assert spec["wind_mps2"][0] <= drawn["wind_mps2"] <= spec["wind_mps2"][1]
        assert all(spec["cam_offset_m"][0] <= v <= spec["cam_offset_m"][1] for v in drawn["cam_offset_m"])
        assert drawn["estimator"] in ("uwb", "flow")


def test_that_a_bad_condition_override_fails_in_one_line():
    with pytest.raises(ForaNavError, match="dropout"):
        cond.preset("moderate", {"dropout": (0.5, 0.1)})
    with pytest.raises(ForaNavError, match="no_such"):
        cond.preset("none", {"no_such": (0, 1)})


def test_that_the_fly_command_replays_a_sweep_flight_exactly(tmp_path):
    # Fixture: a flight with every condition the moderate preset draws
    spec = flight_spec(11, 0, faults="moderate", camera="oracle", ranges=SMALL)
    assert set(spec["conditions"]) >= {"dropout", "pixel_noise_px", "latency_ms", "frame_period_ms",
                                       "wind_mps2", "estimator", "cam_offset_m"}
    map_path = tmp_path / "flight.json"
    fileio.write_json(map_path, spec["map"])
    # Test
    result = fly_task(spec)
    words = fly_command(spec, map_path).split()
    assert words[:2] == ["foranav", "fly"]
    out = subprocess.run([sys.executable, "-m", "host_tools.cli"] + words[1:] + ["--json", "--out",
                                                                                 str(tmp_path / "run")],
                         capture_output=True, text=True, timeout=300)
    # Assert
    assert result["status"] == "ok"
    replayed = json.loads(out.stdout)
    stored = result["summary"]
    assert {k: v for k, v in stored.items() if k not in OUTPUT_KEYS} == \
        {k: v for k, v in replayed.items() if k not in OUTPUT_KEYS}


def test_that_a_flight_that_raises_is_recorded_with_its_traceback_and_reported_as_a_crash(tmp_path):
    # Fixture: a spec whose map is broken (no waypoints)
    good = flight_spec(2, 0, camera="oracle", ranges=SMALL)
    bad = json.loads(json.dumps(flight_spec(2, 1, camera="oracle", ranges=SMALL)))
    bad["map"]["waypoints"] = []
    # Test
    results = [fly_task(good), fly_task(bad)]
    with SweepStore(tmp_path) as store:
        store.start_run(["test"])
        for result in results:
            store.put(result)
        rows = store.rows()
    report = build_report(rows, tmp_path)
    # Assert
    assert [r["status"] for r in rows] == ["ok", "error"]
    assert "waypoints" in rows[1]["traceback"] and "Traceback" in rows[1]["traceback"]
    assert report["failures"]["crash"] == 1 and report["flights"] == 2
    assert report["flawless"] == (1 if rows[0]["summary"]["success"] else 0)
    assert failure_classes(rows[1]) == ["crash"]


def test_that_the_report_lists_every_failed_flight_with_its_replay_commands(tmp_path):
    # Fixture: one flown flight stored twelve times, every other copy failed (a target missed)
    spec = flight_spec(2, 0, camera="oracle", ranges=SMALL)
    flown = fly_task(spec)
    assert flown["status"] == "ok" and flown["summary"]["success"]
    rows = [dict(flown, index=i, spec=dict(spec, seed=100 + i), traceback=None,
                 summary=dict(flown["summary"], missed_targets=[3] if i % 2 else [], success=not i % 2))
            for i in range(12)]
    # Test
    report = build_report(rows, tmp_path)
    text = markdown(report)
    # Assert: all six failures (more than the ten worst would show of a larger sweep), each replayable
    assert [f["index"] for f in report["failed"]] == [1, 3, 5, 7, 9, 11]
    section = text[text.index("## Every failed flight"):]
    for failed in report["failed"]:
        assert "- flight %d (missed target" % failed["index"] in section
        assert failed["fly"] in section and "--seed %d" % (100 + failed["index"]) in failed["fly"]
        assert failed["plantation"] in section


def test_that_the_store_refuses_another_sweep_in_the_same_folder(tmp_path):
    with SweepStore(tmp_path) as store:
        store.check_identity({"seed": 1, "faults": "none"})
        store.check_identity({"seed": 1, "faults": "none"})  # the same sweep again: fine
        with pytest.raises(ForaNavError, match="seed"):
            store.check_identity({"seed": 2, "faults": "none"})


@pytest.mark.parametrize("successes,n", [(0, 10), (5, 10), (99, 100), (500, 500)])
def test_that_the_wilson_interval_contains_the_rate_and_matches_the_closed_form(successes, n):
    import math
    lo, hi = wilson(successes, n)
    p, z = successes / n, 1.959964
    # the Wilson bounds are the roots of (p - q)^2 = z^2 q (1 - q) / n
    for q in (lo, hi):
        if 0.0 < q < 1.0:
            assert abs((p - q) ** 2 - z * z * q * (1 - q) / n) < 1e-9
    assert lo <= p <= hi and 0.0 <= lo and hi <= 1.0
    assert (lo == 0.0) == (successes == 0) and (hi == 1.0) == (successes == n)
    assert math.isclose(hi - lo, wilson(n - successes, n)[1] - wilson(n - successes, n)[0])


def _flown_in_a_row(camera, ranges):
    first = flight_spec(21, 0, camera=camera, ranges=ranges)
    other = flight_spec(21, 1, faults="harsh", camera=camera, ranges=ranges)
    return [fly_task(spec) for spec in (first, other, first)]


def test_that_oracle_flights_in_a_row_in_one_process_leave_no_state_behind():
    # Test: A, then B (harsh faults), then A again in this process
    a, b, a_again = _flown_in_a_row("oracle", SMALL)
    # Assert
    assert a["status"] == b["status"] == a_again["status"] == "ok"
    assert a["summary"] == a_again["summary"] and a["summary"] != b["summary"]


@pytest.mark.slow
def test_that_vision_flights_in_a_row_in_one_process_leave_no_state_behind():
    a, b, a_again = _flown_in_a_row("sim", PlantationRanges(columns=(1, 1), column_length_m=(1.2, 1.2)))
    assert a["status"] == b["status"] == a_again["status"] == "ok"
    assert a["summary"] == a_again["summary"] and a["summary"] != b["summary"]


def test_that_the_progress_bar_shows_flights_done_rate_and_eta():
    import io
    from host_tools.sweep.cmd_sweep import ProgressBar
    stream = io.StringIO()
    bar = ProgressBar(total=12, skipped=2, stream=stream)  # 10 to fly, 2 already stored
    bar(4, 10, 1, 8.0)  # 4 flown in 8 s: 0.5 flights/s, 6 left: 12 s
    bar(10, 10, 1, 20.0)
    first, last = stream.getvalue().splitlines()
    assert "6/12 flights" in first and "0.50 flights/s" in first and "ETA 0m12s" in first and "1 not flawless" in first
    assert "12/12 flights" in last and "ETA 0m00s" in last


def test_that_a_sweeps_own_fly_arguments_reach_every_flight_and_its_replay_command(tmp_path):
    # Fixture: the sweep's --app and --model, as cmd_sweep writes them into each spec
    from host_tools.detection import common

    model = str(common.model_path("oil_palm"))
    plain = flight_spec(3, 0, camera="sim", ranges=SMALL)
    spec = flight_spec(3, 0, camera="sim", ranges=SMALL, fly_args=["--app", "c", "--model", model])
    # Test
    camera_kwargs, options = cond.harness_inputs(spec["conditions"], spec["camera"], spec["fly_args"])
    command = fly_command(spec, tmp_path / "m.json")
    # Assert: the flight gets them, the replay command carries them, a plain sweep's spec has no such key
    assert options["app"] == "c" and camera_kwargs["model"] == model
    assert command.endswith("--app c --model %s" % model)
    assert "fly_args" not in plain and {k: v for k, v in spec.items() if k != "fly_args"} == plain


def test_that_a_c_app_flight_of_a_sweep_flies_like_the_python_one():
    # Fixture: one small oracle plantation, flown by both apps through the sweep's task
    spec = flight_spec(5, 1, camera="oracle", ranges=SMALL)
    c_spec = dict(spec, fly_args=["--app", "c"])
    # Test
    python_result, c_result = fly_task(spec), fly_task(c_spec)
    # Assert: the same flight (the two cores agree step by step, so the summaries match)
    assert python_result["status"] == c_result["status"] == "ok", c_result.get("traceback")
    strip = lambda s: {k: v for k, v in s.items() if k not in OUTPUT_KEYS}  # noqa: E731
    assert strip(c_result["summary"]) == strip(python_result["summary"])
