"""The closed-loop commands as a user runs them: demo, replay (table), paper-tests argument errors."""
from host_tools import cli
from host_tools.demo import progress_line
from host_tools.flight.paper_tests import criteria, table
from tests.conftest import MAP3_SHORT_SENSOR_CLIP

CLIP = MAP3_SHORT_SENSOR_CLIP


def test_that_the_demo_flies_map1_and_says_where_the_outputs_are(tmp_path, capsys):
    code = cli.main(["demo", "--out", str(tmp_path)])
    out = capsys.readouterr().out
    assert code == 0
    assert "SUCCESS" in out and "100%" in out
    for name in ("flight.tlog", "trajectory.png", "summary.json", "detections.csv"):
        assert str(tmp_path / name) in out and (tmp_path / name).stat().st_size > 0


def test_that_the_progress_bar_fills_with_time_but_waits_for_the_end():
    assert progress_line(0, "BOOT", 100).startswith("[" + "-" * 30 + "]   0%")
    assert "[" + "#" * 15 + "-" * 15 + "]  50%" in progress_line(50, "APPROACH", 100)
    assert " 99%" in progress_line(500, "LAND", 100)  # an underestimate never shows 100 % early


def test_that_replay_prints_a_readable_report(capsys):
    assert cli.main(["replay", str(CLIP)]) == 0
    out = capsys.readouterr().out
    assert "31 frames" in out and "tree map (app) vs truth" in out and "setpoints" in out


def test_that_unknown_paper_tests_fail_in_one_line(capsys):
    assert cli.main(["paper-tests", "--tests", "3,12"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--tests" in err[0] and "12" in err[0]


def test_that_the_criteria_and_the_table_name_what_failed():
    entry = {"test": 4, "map": "map2", "situation": "x", "targets": [1, 2, 3], "missed_targets": [3],
             "repeated_targets": [], "non_targets_visited": [7], "spurious_reached": 0, "completed": True,
             "watchdog_events": 0, "mean_deviation_m": 0.02, "ci95_m": 0.01, "mission_time_s": 100.0,
             "recoveries": 1, "vision": {"detections_per_frame": 0.5}}
    entry["passed"] = all(criteria(entry).values())
    assert criteria(entry) == {"completed": True, "every_target_once": False, "no_non_target": False,
                               "no_watchdog": True, "mean_deviation": True}
    row = table([entry])[-1]
    assert "| 2/3 |" in row and "| 7 |" in row and "FAIL: every_target_once, no_non_target" in row
