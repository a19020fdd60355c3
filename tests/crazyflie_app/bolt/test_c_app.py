"""The C flight app (crazyflie_app/bolt via c_core and c_app) on the emulated firmware: boot, deck checks,
arming, PARAM/LOG tables, the C serial parser, and whole flights that match the Python app's."""
import json
import math
import random
import re
import subprocess
import sys

import pytest

from crazyflie_app.bolt import c_core
from crazyflie_app.bolt.c_app import CNavigationApp
from crazyflie_app.firmware import COMMANDER_PRIORITY_DISABLE, Crazyflie, v_task_delay
from crazyflie_app.app.navigation import BOOT_DELAY_MS, LOG_TABLE, PARAM_TABLE, PRE_TAKEOFF_DELAY_MS
from crazyflie_app.app.navigation_core import (PHASE_FOLLOW_PATH, PHASE_NO_CAMERA, PHASE_NO_DECK, PHASE_TAKEOFF,
                                           NavigationParams)
from host_tools.flight import run_flight
from host_tools.flight.oracle import OracleCamera
from host_tools.flight.wire import PtyWire
from host_tools.maps import load_map
from jevois_module.ForaNavTrees import foranav_serial as fs
from tests.conftest import MAP3_SHORT_SENSOR_CLIP, REPO_ROOT

from ..conftest import console_text as console

REPO = REPO_ROOT
APP_SOURCE = REPO / "crazyflie_app" / "bolt" / "src" / "foranav_app.c"
TABLE_SOURCES = {"PARAM": APP_SOURCE.with_name("foranav_params.c"), "LOG": APP_SOURCE.with_name("foranav_log.c")}
PATH = ((0.0, 0.0), (3.0, 0.0))
MAX_MEAN_DEVIATION_M = 0.05


@pytest.fixture
def wired_cf():
    """make(camera=True, **Crazyflie kwargs): a Crazyflie with a pty on UART2 and, with camera, a camera task
    sending an empty frame (MARK STOP) every 100 ms, as the module does on the ground."""
    wire = PtyWire()
    made = []

    def make(camera=True, **kwargs):
        cf = Crazyflie(seed=1, **kwargs)
        cf.attach_uart2(wire.slave_path)
        if camera:
            cf.x_task_create(empty_frames(wire), "CAM", 6)
        made.append(cf)
        return cf

    yield make
    for cf in made:
        cf.uart2.close()
    wire.close()


def empty_frames(wire, period_ms=100):
    while True:
        wire.write(fs.FRAME_STOP.encode() + b"\r\n")
        yield v_task_delay(period_ms)


def test_that_without_a_flow_deck_the_c_app_stops_and_never_commands(wired_cf):
    cf = wired_cf(decks=("bcLoco",))
    app = CNavigationApp(cf, PATH)
    app.start()
    cf.run_until(20000)
    assert "No flow deck installed, aborting" in console(cf)
    assert app.phase == PHASE_NO_DECK
    assert cf.commander.commander_get_active_priority() == COMMANDER_PRIORITY_DISABLE
    assert cf.model.truth.z == 0.0 and not cf.supervisor_is_armed()


def test_that_the_c_app_arms_after_its_checks_and_takes_off_to_the_altitude_param(wired_cf):
    cf = wired_cf()
    app = CNavigationApp(cf, PATH)
    app.start()
    cf.registry.param_set("app.altitude", 1.0)  # lands in the C struct
    assert app.core.params.altitude_m == 1.0
    cf.run_until(BOOT_DELAY_MS + PRE_TAKEOFF_DELAY_MS - 100)
    assert not cf.supervisor_is_armed()  # the camera check comes last, then arming
    cf.run_until(BOOT_DELAY_MS + PRE_TAKEOFF_DELAY_MS + 100)
    assert cf.supervisor_is_armed() and "Armed" in console(cf)
    assert app.phase == PHASE_TAKEOFF
    cf.run_until(BOOT_DELAY_MS + PRE_TAKEOFF_DELAY_MS + 8000)
    assert app.phase == PHASE_FOLLOW_PATH
    assert cf.model.truth.z == pytest.approx(1.0, abs=0.05)
    assert cf.registry.log_read("app.phase") == PHASE_FOLLOW_PATH
    assert "phase FOLLOW_PATH" in console(cf)


def test_that_the_c_app_never_arms_nor_takes_off_without_a_camera(wired_cf):
    cf = wired_cf(camera=False)
    app = CNavigationApp(cf, PATH)
    app.start()
    cf.run_until(BOOT_DELAY_MS + PRE_TAKEOFF_DELAY_MS + 25000)
    assert app.phase == PHASE_NO_CAMERA
    assert not cf.supervisor_is_armed() and cf.model.truth.z == 0.0
    assert "Waiting for the camera" in console(cf) and "No camera heard for 20.0 s, not taking off" in console(cf)


def test_that_the_c_params_mirror_the_python_params_field_by_field():
    defaults = c_core.c_params()
    assert set(c_core.PARAM_NAMES) == set(NavigationParams.__dataclass_fields__)
    for name in c_core.PARAM_NAMES:
        assert getattr(defaults, name) == getattr(NavigationParams(), name), name


def _c_table(kind):
    """(type, name) of every PARAM_ADD / LOG_ADD of the app group (foranav_params.c, foranav_log.c)."""
    text = TABLE_SOURCES[kind].read_text()
    block = re.search(r"%s_GROUP_START\(app\)(.*?)%s_GROUP_STOP\(app\)" % (kind, kind), text, re.S).group(1)
    return re.findall(r"%s_ADD\((\w+), (\w+), &" % kind, block)


def test_that_the_bolt_app_declares_the_python_apps_param_and_log_tables():
    c_types = {"PARAM_FLOAT": "float", "PARAM_UINT8": "uint8_t", "PARAM_UINT16": "uint16_t",
               "PARAM_UINT32": "uint32_t", "LOG_FLOAT": "float", "LOG_UINT8": "uint8_t", "LOG_UINT16": "uint16_t",
               "LOG_UINT32": "uint32_t"}
    assert [(c_types[t], n) for t, n in _c_table("PARAM")] == [(e.type, e.name) for e in PARAM_TABLE.entries]
    assert [(c_types[t], n) for t, n in _c_table("LOG")] == [(e.type, e.name) for e in LOG_TABLE.entries]
    text = APP_SOURCE.read_text()
    for call in ("commanderSetSetpoint(&setpoint, COMMANDER_PRIORITY_EXTRX)", "uart2GetDataWithTimeout(",
                 "supervisorRequestArming(true)", "logGetVarId(\"stateEstimate\"", "logGetFloat(", "void appMain"):
        assert call in text


TRICKY_LINES = [b"T2 0 0", b"T2 -1000 -750", b"T2 1000 750", b"T2 1001 0", b"T2 0 -751", b"T2 1_000 -7_5",
                b"T2 1__0 0", b"T2 _1 0", b"T2 1_ 0", b"T2 +5 -.5", b"T2 5. 1e2", b"T2 1e999 0", b"T2 inf 0",
                b"T2 nan 0", b"T2 0x10 0", b"T2 1 2 3", b"T2 15", b"  T2\t3\x0b4  ", b"T2 3\x1c4",
                b"N2 oil_palm 12 -40 100 80", b"N2 x 0 0 2001 0", b"N2 x 0 0 -1 0", b"N2 x 0 0 10",
                b"MARK START", b"MARK STOP", b"MARK  STOP ", b"MARK PAUSE", b"mark stop", b"OK", b"",
                b"ERR Unsupported command [foo]", b"T2 \xc3\xa9 0", b"T2 1e3 -1E2", b"T2 -0 +0", b"T2 1e 0"]


def _python_parse(line):
    m = fs.parse_line(line)
    if m is None:
        return None
    if isinstance(m, fs.FrameMark):
        return ("MARK " + m.what,)
    return (m.kind, m.label if m.kind == "N2" else "", m.x, m.y, m.w or 0.0, m.h or 0.0)


def _c_parse(line):
    kind, label, x, y, w, h = c_core.parse_line(line)
    if kind is None:
        return None
    if kind.startswith("MARK"):
        return (kind,)
    return (kind, label, x, y, w, h)


def test_that_the_c_parser_reads_every_line_as_the_python_grammar_does():
    rng = random.Random(13)
    alphabet = b"T2N MARKSTOP0123456789-+._eE\t"
    fuzz = [bytes(rng.choice(alphabet) for _ in range(rng.randint(1, 20))) for _ in range(3000)]
    fuzz += [b"T2 " + bytes(rng.choice(b"0123456789-_.e") for _ in range(rng.randint(1, 6))) + b" 0"
             for _ in range(2000)]
    for line in TRICKY_LINES + fuzz:
        assert _c_parse(line) == _python_parse(line), line


def test_that_the_c_line_assembler_drops_overlong_lines_whole_and_takes_any_terminator(wired_cf):
    cf = wired_cf()
    app = CNavigationApp(cf, PATH)
    app.core.feed(b"X" * 65 + b"\r\n" + b"T2 0 0\x00T2 1 1\rMARK STOP\n", 0, None, False)
    assert app.core.lines_dropped == 1
    assert app.core.frames == 0  # frames before the estimate is ready are dropped ...
    assert app.core.last_frame_points == []
    frames = app.core.feed(b"T2 0 0\nT2 -1000 0\nMARK STOP\n", 10, (0.0, 0.0, 1.25, 0.0, 0.0, 0.0), True)
    assert [len(dets) for dets, _, _ in frames] == [2]  # ... once it is, a frame ends at its MARK
    (dets, ids, points), = frames
    assert dets[1] == (0.0, 144.0)
    assert points[1] == pytest.approx((0.0, 176.0 * 1.25 * 0.0031))


def fly(app, camera="oracle", seed=0, **options):
    pmap = load_map("map1")
    cam = OracleCamera(pmap, seed=seed)
    return run_flight(pmap, cam, seed=seed, options=dict(options, app=app))


def test_that_the_c_app_flies_map1_exactly_like_the_python_app():
    pmap = load_map("map1")
    runs = {app: run_flight(pmap, OracleCamera(pmap, seed=3), seed=3, options={"app": app}) for app in ("python", "c")}
    c, py = runs["c"], runs["python"]
    assert c["success"] and c["mean_deviation_m"] <= MAX_MEAN_DEVIATION_M
    assert c["missed_targets"] == [] and c["repeated_targets"] == [] and c["non_targets_visited"] == []
    for key in ("reached", "mission_time_s", "detections", "out_of_column_detections", "recoveries", "watchdog"):
        assert c[key] == py[key], key


@pytest.mark.slow
def test_that_both_apps_write_the_same_tlog_bytes(tmp_path):
    pmap = load_map("map2")
    for app in ("python", "c"):
        run_flight(pmap, OracleCamera(pmap, seed=5), seed=5, out_dir=tmp_path / app, options={"app": app})
    # same setpoints, same console lines (STATUSTEXT), same ticks
    assert (tmp_path / "c" / "flight.tlog").read_bytes() == (tmp_path / "python" / "flight.tlog").read_bytes()


def test_that_the_c_app_recovers_a_hidden_tree_and_holds_through_a_silent_link():
    summary = fly("c", seed=1, hide_tree=3, hide_s=5.0, silence=[(40.0, 2.0)])
    assert summary["success"], summary
    assert summary["recoveries"] >= 1 and summary["link_losses"] == 1


@pytest.mark.slow
def test_that_foranav_fly_takes_the_c_app(tmp_path):
    result = subprocess.run([sys.executable, "-m", "host_tools.cli", "fly", "--map", "map1", "--camera", "oracle",
                             "--app", "c", "--json", "--out", str(tmp_path / "fly")],
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    summary = json.loads(result.stdout)
    assert summary["success"] and summary["mean_deviation_m"] <= MAX_MEAN_DEVIATION_M
    assert not math.isnan(summary["mean_deviation_m"])


@pytest.mark.slow
def test_that_a_replay_with_the_c_app_reports_what_the_python_app_does():
    from host_tools.flight.replay import expectation_record, replay_clip
    from host_tools.sim.clip import read_clip

    clip = read_clip(MAP3_SHORT_SENSOR_CLIP)
    python, c = replay_clip(clip), replay_clip(clip, app="c")
    assert expectation_record(c) == expectation_record(python)
    assert c["setpoints"] == python["setpoints"] and c["tree_map"] == python["tree_map"]
