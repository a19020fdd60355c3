"""The app on the emulated firmware: boot and deck checks, camera lines, PARAM/LOG tables, a short flight."""
import math

import pytest

from crazyflie_app.firmware import COMMANDER_PRIORITY_DISABLE, Crazyflie, MavModelConfig, v_task_delay
from crazyflie_app.app.navigation import (BOOT_DELAY_MS, LOG_TABLE, PARAM_TABLE, PRE_TAKEOFF_DELAY_MS, NavigationApp)
from crazyflie_app.app.navigation_core import PHASE_FOLLOW_PATH, PHASE_NO_DECK, PHASE_TAKEOFF
from jevois_module.ForaNavTrees import foranav_serial as fs

from tests.crazyflie_app.conftest import console_text

PATH = ((0.0, 0.0), (3.0, 0.0))
ALTITUDE_TOLERANCE = 0.05
BOOTED_MS = BOOT_DELAY_MS + 10


CAMERA_FRAME_MS = 111  # the paper's 9 fps


def make_app(decks=("bcFlow2", "bcLoco"), camera=False, **model):
    """The app on loop://; ``camera``: a camera that sees nothing but ends a frame every CAMERA_FRAME_MS (the
    app takes off only once it has heard the camera)."""
    cf = Crazyflie(seed=1, decks=decks, model_config=MavModelConfig(**model))
    app = NavigationApp(cf, PATH, "loop://")
    app.start()
    if camera:
        cf.x_task_create(empty_frames(app), "TEST_CAMERA", 6)
    return cf, app


def empty_frames(app):
    while True:
        if app.link.port is not None:
            app.link.port.write(b"MARK START\r\nMARK STOP\r\n")
        yield v_task_delay(CAMERA_FRAME_MS)


def test_that_without_a_flow_deck_the_app_stops_and_never_commands():
    cf, app = make_app(decks=("bcLoco",))
    cf.run_until(20000)
    assert "No flow deck installed, aborting" in console_text(cf)
    assert app.phase == PHASE_NO_DECK
    assert cf.commander.commander_get_active_priority() == COMMANDER_PRIORITY_DISABLE
    assert cf.model.truth.z == 0.0
    assert "APP" not in cf.scheduler.task_names()  # appMain returned: the task parked


def test_that_without_a_loco_deck_the_app_warns_and_flies():
    cf, app = make_app(decks=("bcFlow2",), camera=True)
    cf.run_until(BOOT_DELAY_MS + PRE_TAKEOFF_DELAY_MS + 100)
    assert any("No Loco deck" in line for line in console_text(cf))
    assert app.phase == PHASE_TAKEOFF


def test_that_the_app_takes_off_to_the_altitude_param_and_follows_the_path():
    cf, app = make_app(camera=True)
    cf.registry.param_set("app.altitude", 1.0)
    cf.run_until(BOOT_DELAY_MS + PRE_TAKEOFF_DELAY_MS + 8000)
    assert app.phase == PHASE_FOLLOW_PATH
    assert cf.model.truth.z == pytest.approx(1.0, abs=ALTITUDE_TOLERANCE)
    assert cf.model.truth.vx == pytest.approx(0.1, abs=0.02)  # cruise speed
    assert cf.supervisor.watchdog_events == []


def test_that_detection_lines_are_taken_and_everything_else_ignored():
    # Fixture: a booted app (estimate ids resolved), the camera writing into the loop port
    cf, app = make_app()
    cf.run_until(BOOTED_MS)
    cf.model.truth.z = 1.25  # at flight height the two detections below are 0.55 m apart on the ground
    cf.run_until(BOOTED_MS + 10)
    camera = app.link.port
    # Test: one frame with a T2 and an N2 among console noise, then an unterminated T2
    camera.write(b"OK\r\nALIVE\r\nERR Unknown command\r\n" + fs.format_t2(176, 44, 352, 288).encode()
                 + b"\r\n\x07\x08garbage\r\n" + fs.format_n2("oil_palm", 76, 144, 80, 80, 352, 288).encode()
                 + b"\r\nMARK STOP\r\nT2 0 0")
    cf.run_until(BOOTED_MS + 30)
    # Assert: one frame with two detections (two trees 0.55 m apart: one frame never merges them); the
    # unterminated T2 waits for its line end
    assert app.frames == 1
    assert app.core.counters.detections == 2
    assert app.num_trees == 2
    camera.write(b"\r\nMARK STOP\r\n")
    cf.run_until(BOOTED_MS + 50)
    assert app.frames == 2 and app.core.counters.detections == 3


def test_that_detections_become_trees_at_the_camera_model_position():
    cf, app = make_app(position_noise_m=0.0, position_bias_m=0.0)
    cf.run_until(BOOTED_MS)
    cf.model.truth.z = 1.25  # as if hovering: the estimate follows on the next stabilizer step
    cf.run_until(BOOTED_MS + 20)
    app.link.port.write((fs.format_t2(176, 44, 352, 288) + "\r\nMARK STOP\r\n").encode())
    cf.run_until(BOOTED_MS + 40)
    (tree,) = app.core.memory.trees.values()
    assert tree.x == pytest.approx(100 * 1.25 * 0.0031, abs=0.005)
    assert tree.y == pytest.approx(0.0, abs=0.005)


def test_that_every_param_is_documented_with_units_and_paper_defaults():
    cf, app = make_app()
    for entry in PARAM_TABLE.entries:
        assert entry.doc, entry.name
        assert entry.unit or entry.name in ("columnFactor", "minHits", "treeCapacity", "visitedCap", "frameCap",
                                            "servoKiBand", "anchorMin", "anchorGain", "start"), entry.name
    read = cf.registry.param_read
    assert read("app.altitude") == pytest.approx(1.25)
    assert read("app.cruiseSpeed") <= 0.1 + 1e-9
    assert read("app.captureRadius") == 40
    assert read("app.recoveryDist") == pytest.approx(0.7)
    assert read("app.mergeRadius") == pytest.approx(0.45)
    assert read("app.columnFactor") == pytest.approx(1.5)
    assert read("app.camScale") == pytest.approx(0.0031)
    assert read("app.camOffsetX") == 0.0 and read("app.camOffsetY") == 0.0


def test_that_every_log_variable_reads_through_the_firmware_api():
    cf, app = make_app()
    cf.run_until(BOOTED_MS)
    for entry in LOG_TABLE.entries:
        var_id = cf.log_get_var_id("app", entry.name)
        value = cf.log_get_float(var_id)
        assert isinstance(value, float)
        assert entry.type == "float" or not math.isnan(value)
    assert cf.log_get_float(cf.log_get_var_id("app", "phase")) == 0.0  # BOOT


def test_that_params_are_range_checked():
    cf, app = make_app()
    with pytest.raises(AssertionError):
        cf.registry.param_set("app.minHits", 300)  # uint8
    with pytest.raises(KeyError):
        cf.registry.param_set("app.noSuchParam", 1)


def test_that_n2_lines_of_another_species_are_ignored():
    cf = Crazyflie(seed=1)
    app = NavigationApp(cf, PATH, "loop://", target_label="oil_palm")
    app.start()
    cf.run_until(BOOTED_MS)
    app.link.port.write(b"N2 coconut 0 0 100 100\r\nN2 oil_palm 0 0 100 100\r\nMARK STOP\r\n")
    cf.run_until(BOOTED_MS + 20)
    assert app.core.counters.detections == 1 and app.other_labels == 1


def test_that_the_app_package_depends_only_on_the_serial_grammar_of_ours():
    # DESIGN.md: crazyflie_app imports jevois_module.ForaNavTrees.foranav_serial and never host_tools
    import ast
    from pathlib import Path

    import crazyflie_app

    root = Path(crazyflie_app.__file__).parent
    for path in root.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else \
                [node.module or ""] if isinstance(node, ast.ImportFrom) else []
            for name in names:
                assert not name.startswith("host_tools"), path
                assert not name.startswith("jevois_module") or name in (
                    "jevois_module.ForaNavTrees", "jevois_module.ForaNavTrees.foranav_serial"), path
