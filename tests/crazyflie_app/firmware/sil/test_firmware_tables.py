"""The firmware plant serves the firmware's own LOG/PARAM tables: the groups are those the compiled firmware
files declare, reads and writes reach the firmware's variables, kalman.resetEstimation resets the filter, a PID
gain written changes the flight, stabilizer.estimator/controller answer for what runs."""
import re
from pathlib import Path

import pytest

from crazyflie_app.firmware import COMMANDER_PRIORITY_EXTRX, Crazyflie, setpoint_t, v_task_delay
from crazyflie_app.firmware.commander import modeAbs
from crazyflie_app.firmware.sil import BUILD_DIR
from crazyflie_app.firmware.sil.build import FIRMWARE_SOURCES, INCLUDED_FIRMWARE_SOURCES, LOOP_FILES
from crazyflie_app.firmware.sil.stack import FirmwarePlantConfig

from ..conftest import hover
from .conftest import needs_firmware_plant

pytestmark = needs_firmware_plant

# groups the issue and stock cflib examples name (basiclog: stabilizer.roll, basicparam: pid_attitude.pitch_kd,
# the autonomy examples: kalman.resetEstimation / kalman.stateX, the high-level one: stabilizer.controller)
EXPECTED_LOG = ("stabilizer.roll", "stabilizer.pitch", "stabilizer.yaw", "stabilizer.thrust", "stateEstimate.x",
                "kalman.stateX", "kalman.varPX", "ctrltarget.x", "posCtl.targetVZ", "pid_attitude.roll_outP",
                "supervisor.info", "sys.isFlying", "motor.m1req", "motor.m1", "pm.vbat", "stateEstimateZ.z")
EXPECTED_PARAM = ("stabilizer.estimator", "stabilizer.controller", "stabilizer.stop", "pid_attitude.pitch_kd",
                  "pid_rate.roll_kp", "posCtlPid.zKp", "velCtlPid.vzKp", "kalman.resetEstimation",
                  "kalman.initialX", "commander.enHighLevel", "supervisor.infdmp", "powerDist.idleThrust",
                  "led.bitmask", "cpu.flash", "deck.bcFlow2")
# compiled out in this configuration (stabilizer.c: #ifdef LOG_SEC_IMU)
CONDITIONAL_GROUPS = {"accSec", "gyroSec"}
HOVER_Z_M = 0.5


def firmware_cf(seed=0, **config):
    return Crazyflie(seed=seed, plant="firmware", model_config=FirmwarePlantConfig(**config), start=(0.0, 0.0, 0.0),
                     bounds=(0.0, 0.0, 4.0, 2.0))


def _firmware_root() -> Path:
    roots = list((BUILD_DIR / "unpacked").glob("*/src/modules")) + list(BUILD_DIR.glob("crazyflie-firmware/src/modules"))
    if not roots:
        pytest.skip("the firmware source the plant was built from is not unpacked in build/firmware-sil")
    return roots[0].parent.parent


def _declared_groups(kind: str) -> set[str]:
    root = _firmware_root()
    files = [root / f for f in FIRMWARE_SOURCES + LOOP_FILES + INCLUDED_FIRMWARE_SOURCES if f.endswith(".c")]
    return {name for path in files for name in re.findall(r"^\s*%s_GROUP_START\((\w+)\)" % kind,
                                                          path.read_text(), re.M)}


def _served_groups(names) -> set[str]:
    return {name.split(".")[0] for name in names}


def test_that_every_group_the_compiled_firmware_declares_is_served_and_nothing_else():
    # Fixture
    cf = firmware_cf()
    tables = cf.stack.tables
    # Assert: the firmware's tables are exactly the groups its compiled files declare (less #ifdef'd ones)
    declared_log, declared_param = _declared_groups("LOG"), _declared_groups("PARAM")
    assert _served_groups(tables.log_names()) == declared_log - CONDITIONAL_GROUPS
    assert _served_groups(tables.param_names()) == declared_param
    assert not tables.skipped
    names = set(cf.registry.log_names())
    params = {name for name, _ in cf.registry.param_entries()}
    assert set(EXPECTED_LOG) <= names and set(EXPECTED_PARAM) <= params
    cf.close()


def test_that_read_only_flags_come_from_the_firmware():
    cf = firmware_cf()
    entries = dict(cf.registry.param_entries())
    # cpu.* are PARAM_RONLY stand-ins, the kalman/pid params are writable in the firmware
    assert entries["cpu.flash"].read_only and not entries["pid_attitude.pitch_kd"].read_only
    assert not entries["kalman.resetEstimation"].read_only
    cf.close()


def _pilot(cf, setpoint_at, until_ms, arm_at_ms=500):
    def task():
        sp = setpoint_t()
        while True:
            now = cf.x_task_get_tick_count()
            if now == arm_at_ms:
                cf.supervisor_request_arming(True)
            if now >= arm_at_ms:
                cf.commander_set_setpoint(setpoint_at(sp), COMMANDER_PRIORITY_EXTRX)
            yield v_task_delay(10)
    cf.x_task_create(task(), "PILOT", 1)
    cf.run_until(until_ms)


def test_that_kalman_reset_estimation_reinitialises_the_filter_at_the_initial_position():
    # Fixture: a booted firmware on the ground at (0, 0), the Flow deck alone (no ranging pulls x back)
    cf = firmware_cf(positioning="flow")
    cf.run_until(1000)
    assert abs(cf.registry.log_read("kalman.stateX")) < 0.1
    # Test: as cflib's reset_estimator does (after moving the initial position)
    cf.registry.param_set("kalman.initialX", 2.5)
    cf.registry.param_set("kalman.resetEstimation", 1)
    cf.run_until(1100)
    # Assert: the filter restarted at the new initial x; the flag is cleared by the Kalman task, as the firmware's
    assert cf.registry.log_read("kalman.stateX") == pytest.approx(2.5, abs=0.01)
    assert cf.registry.param_read("kalman.resetEstimation") == 0
    cf.close()


def test_that_a_pid_gain_written_changes_the_flight():
    # Fixture: two identical hovers to 0.5 m; in the second, the z position loop's gains are written to 0
    heights = []
    for scale in (1.0, 0.0):
        cf = firmware_cf()
        for gain in ("posCtlPid.zKp", "posCtlPid.zKi"):
            cf.registry.param_set(gain, cf.registry.param_read(gain) * scale)
        _pilot(cf, lambda sp: hover(sp, z=HOVER_Z_M), 2500)
        heights.append(cf.model.truth.z)
        cf.close()
    # Assert: the firmware's z loop used the written gains: without them no climb is asked for
    assert heights[0] > 0.35
    assert heights[1] < 0.1


def _position_hold(sp, z):
    sp.mode.x = sp.mode.y = sp.mode.z = modeAbs
    sp.position.x, sp.position.y, sp.position.z = 0.0, 0.0, z
    return sp


def test_that_stabilizer_controller_and_estimator_read_what_runs():
    cf = firmware_cf()
    cf.run_until(100)
    assert cf.registry.param_read("stabilizer.estimator") == 2  # Kalman: the Flow deck requires it
    assert cf.registry.param_read("stabilizer.controller") == 1  # PID
    # Test: ask for Mellinger (2), as the high-level example does, and for the complementary estimator (1)
    cf.registry.param_set("stabilizer.controller", 2)
    cf.registry.param_set("stabilizer.estimator", 1)
    cf.run_until(102)
    # Assert: the ones compiled here keep running, the variables say so, the console tells why
    assert cf.registry.param_read("stabilizer.controller") == 1
    assert cf.registry.param_read("stabilizer.estimator") == 2
    lines = [text for _, module, text in cf.console.lines if module == "STAB"]
    assert any("controller 2" in text for text in lines) and any("estimator 1" in text for text in lines)
    cf.close()


def test_that_logged_firmware_variables_follow_the_flight():
    # Fixture: a hover at 0.5 m
    cf = firmware_cf()
    _pilot(cf, lambda sp: _position_hold(sp, HOVER_Z_M), 4000)
    # Assert: the firmware's own variables: the estimate, the setpoint, the loop's rate counter
    assert cf.registry.log_read("stateEstimate.z") == pytest.approx(cf.model.truth.z, abs=0.05)
    assert cf.registry.log_read("ctrltarget.z") == pytest.approx(HOVER_Z_M)
    assert cf.registry.log_read("stateEstimateZ.z") == int(cf.registry.log_read("stateEstimate.z") * 1000)
    assert cf.registry.log_read("stabilizer.rtStab") == pytest.approx(1000, rel=0.01)
    assert cf.registry.log_read("sys.isFlying") == 1
    cf.close()
    # after power-off the tables keep their last values instead of reading unmapped memory
    assert cf.registry.log_read("ctrltarget.z") == pytest.approx(HOVER_Z_M)
