"""foranav fly: JSON and table output, default output folder, --camera sim, bad arguments, --crtp in use."""
import json
import socket
from pathlib import Path

from host_tools import cli

SUMMARY_KEYS = {"completed", "targets", "reached", "non_targets_visited", "mean_deviation_m", "ci95_m",
                "mission_time_s", "recoveries", "watchdog_events", "tlog", "plot"}


def test_that_fly_json_prints_the_summary_and_writes_the_outputs(tmp_path, capsys):
    code = cli.main(["fly", "--map", "map1", "--camera", "oracle", "--seed", "3", "--out", str(tmp_path),
                     "--json", "--dropout", "0.1"])
    summary = json.loads(capsys.readouterr().out)
    assert code == 0
    assert SUMMARY_KEYS <= set(summary)
    assert summary["completed"] and summary["seed"] == 3
    assert all(set(r) == {"id", "deviation_m", "t_s"} for r in summary["reached"])
    for name in ("flight.tlog", "trajectory.png", "summary.json"):
        assert (tmp_path / name).stat().st_size > 0
    assert json.loads((tmp_path / "summary.json").read_text())["reached"] == summary["reached"]


def test_that_fly_defaults_to_a_runs_folder_and_prints_a_table(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code = cli.main(["fly", "--map", "map2", "--camera", "oracle", "--hide-tree", "5", "--hide-s", "5"])
    out = capsys.readouterr().out
    assert code == 0
    assert "SUCCESS" in out and "recoveries 1" in out
    assert (tmp_path / "runs" / "fly-map2-seed0" / "flight.tlog").exists()


def test_that_realtime_only_options_without_realtime_fail_in_one_line(capsys):
    assert cli.main(["fly", "--map", "map1", "--camera", "oracle", "--kill-camera-at", "9"]) == 2
    err = capsys.readouterr().err
    assert "--kill-camera-at" in err and len(err.strip().splitlines()) == 1


def test_that_bad_arguments_fail_in_one_line_and_write_nothing(tmp_path, capsys):
    out = tmp_path / "never"
    assert cli.main(["fly", "--map", "map1", "--dropout", "1.5", "--out", str(out)]) == 2
    assert cli.main(["fly", "--map", "no_such_map", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2 and "--dropout" in err[0] and "no_such_map" in err[1]
    assert not Path(out).exists()


def test_that_a_bad_mavlink_url_fails_cleanly(tmp_path, capsys):
    assert cli.main(["fly", "--map", "map1", "--out", str(tmp_path), "--mavlink", "udpout:localhost:notaport"]) == 2
    assert "--mavlink" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_that_a_crtp_port_in_use_fails_in_one_line_and_writes_nothing(tmp_path, capsys):
    out = tmp_path / "never"
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as taken:
        taken.bind(("127.0.0.1", 0))
        port = taken.getsockname()[1]
        assert cli.main(["fly", "--map", "map1", "--camera", "oracle", "--out", str(out),
                         "--crtp", "127.0.0.1:%d" % port]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--crtp 127.0.0.1:%d" % port in err[0]
    assert not out.exists()
