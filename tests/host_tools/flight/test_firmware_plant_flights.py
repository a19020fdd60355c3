"""foranav fly --plant firmware: the app flies a map on the real firmware's controller and Kalman estimator,
both apps the same, the same seed the same bytes, and a plant that is not built is one line, exit 2."""
import json
from pathlib import Path

import pytest

from host_tools import cli
from tests.crazyflie_app.firmware.sil.conftest import needs_firmware_plant

MAX_MEAN_DEVIATION_M = 0.10  # the paper's criterion
MAX_ESTIMATE_ERROR_M = 0.20  # p95 of the Kalman estimate's horizontal error on an oracle flight


def fly_json(capsys, *arguments):
    code = cli.main(["fly", "--json", *arguments])
    return code, json.loads(capsys.readouterr().out)


@pytest.fixture(scope="module")
def python_and_c_flights(tmp_path_factory):
    """Map 1 with the oracle camera on the firmware plant, once with each app."""
    root = tmp_path_factory.mktemp("firmware_flights")
    flights = {}
    for app in ("python", "c"):
        out = root / app
        assert cli.main(["fly", "--map", "map1", "--camera", "oracle", "--plant", "firmware", "--app", app,
                         "--out", str(out), "--json"]) == 0
        flights[app] = (json.loads((out / "summary.json").read_text()), (out / "flight.tlog").read_bytes())
    return flights


@needs_firmware_plant
def test_that_the_app_reaches_every_target_on_the_firmware_plant(python_and_c_flights):
    # Fixture
    summary, _ = python_and_c_flights["python"]
    # Assert
    assert summary["success"] and summary["plant"] == "firmware" and not summary["crashed"]
    assert summary["missed_targets"] == [] and summary["non_targets_visited"] == []
    assert summary["mean_deviation_m"] <= MAX_MEAN_DEVIATION_M
    assert 0 < summary["estimate_error"]["position_m"]["p95"] < MAX_ESTIMATE_ERROR_M


@needs_firmware_plant
def test_that_both_apps_fly_the_same_on_the_firmware_plant(python_and_c_flights):
    # Assert: the same inputs give the same setpoints, so the same firmware run, byte for byte
    (python_summary, python_tlog), (c_summary, c_tlog) = python_and_c_flights["python"], python_and_c_flights["c"]
    assert python_tlog == c_tlog
    assert python_summary["reached"] == c_summary["reached"]


@needs_firmware_plant
def test_that_the_same_seed_gives_the_same_firmware_flight(python_and_c_flights, tmp_path):
    # Test: the Python app's flight again, in this process (the fixture's flights ran here too)
    assert cli.main(["fly", "--map", "map1", "--camera", "oracle", "--plant", "firmware", "--out", str(tmp_path),
                     "--json"]) == 0
    # Assert
    assert (tmp_path / "flight.tlog").read_bytes() == python_and_c_flights["python"][1]


def test_that_an_unbuilt_firmware_plant_is_one_line_and_exit_2(tmp_path, capsys, monkeypatch):
    # Fixture
    monkeypatch.setenv("FORANAV_SIL_LIB", str(tmp_path / "missing" / "libforanav_sil.so"))
    out = tmp_path / "never"
    # Test
    code = cli.main(["fly", "--map", "map1", "--camera", "oracle", "--plant", "firmware", "--out", str(out)])
    # Assert
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1
    assert "--plant firmware" in err[0] and "make firmware-sil" in err[0]
    assert not out.exists()


@pytest.mark.parametrize("command", [["paper-tests", "--tests", "1"], ["demo"], ["sweep", "--count", "1"]])
def test_that_every_command_with_plant_refuses_an_unbuilt_firmware_plant(command, tmp_path, capsys, monkeypatch):
    # Fixture
    monkeypatch.setenv("FORANAV_SIL_LIB", str(tmp_path / "missing.so"))
    out = tmp_path / "never"
    # Test
    code = cli.main(command + ["--plant", "firmware", "--out", str(out)])
    # Assert
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "make firmware-sil" in err[0]
    assert not out.exists()
