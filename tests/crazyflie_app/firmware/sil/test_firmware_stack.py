"""The firmware plant on the emulated Crazyflie: the real firmware's supervisor arms and guards, its controller
flies the rigid body where the setpoints say, its Kalman filter's estimate stays near the truth, the crash
rule ends a fall, and every boot starts from a powered-off firmware."""
import math

import pytest

from crazyflie_app.firmware import Crazyflie, setpoint_t, COMMANDER_PRIORITY_EXTRX, v_task_delay
from crazyflie_app.firmware.commander import modeAbs
from crazyflie_app.firmware.sil.stack import FirmwarePlantConfig
from crazyflie_app.firmware.supervisor import FLYING, LOCKED, PRE_FLIGHT, READY_TO_FLY, WARNING_LEVEL_OUT

from ..conftest import HEIGHT, HEIGHT_TOLERANCE, hover
from .conftest import needs_firmware_plant

pytestmark = needs_firmware_plant

ARM_AT_MS = 500
SETPOINT_PERIOD_MS = 10
ESTIMATE_TOLERANCE_M = 0.10  # position estimate error of a calm hover (UWB + flow)
PULSE_DISTANCE_M = (0.7, 1.05)  # how far 2 s at 0.5 m/s carry the MAV (1 m, less the velocity loop's lag)
DRIFT_TOLERANCE_M = 0.15
MIN_NLOS_DROPPED = 10
SUPERVISOR_PERIOD_MS = 40  # supervisorUpdate runs at RATE_25_HZ


def firmware_cf(seed=0, **config):
    return Crazyflie(seed=seed, plant="firmware", model_config=FirmwarePlantConfig(**config), start=(0.0, 0.0, 0.0),
                     bounds=(0.0, 0.0, 4.0, 2.0))


def pilot(cf, until_ms, setpoint_at, arm_at_ms=ARM_AT_MS):
    """A task that arms at ``arm_at_ms`` and streams ``setpoint_at(t_ms)`` (None: stop sending) every 10 ms."""
    def task():
        sp = setpoint_t()
        while True:
            now = cf.x_task_get_tick_count()
            if now == arm_at_ms:
                cf.supervisor_request_arming(True)
            if now >= arm_at_ms:
                wanted = setpoint_at(now)
                if wanted is not None:
                    cf.commander_set_setpoint(wanted(sp), COMMANDER_PRIORITY_EXTRX)
            yield v_task_delay(SETPOINT_PERIOD_MS)
    cf.x_task_create(task(), "PILOT", 1)
    cf.run_until(until_ms)


def test_that_the_supervisor_keeps_the_motors_off_until_armed():
    # Fixture
    cf = firmware_cf()
    # Test: no arming request in 2.9 s (the pilot would only arm at t = 10^9 ms)
    pilot(cf, 2900, lambda t: hover, arm_at_ms=10 ** 9)
    # Assert: the Bolt requires arming; the supervisor nulls every setpoint until then
    assert cf.supervisor.state == PRE_FLIGHT and cf.model.truth.z == 0.0
    assert max(cf.model.stack.status.motor_ratio) == 0.0
    cf.close()


def test_that_an_armed_firmware_takes_off_and_holds_the_height():
    # Fixture
    cf = firmware_cf()
    # Test
    pilot(cf, 8000, lambda t: hover)
    # Assert
    states = [state for _, state in cf.supervisor.events]
    assert states[-3:] == ["ARMING", READY_TO_FLY, FLYING]
    assert PRE_FLIGHT in states[:-3]
    assert abs(cf.model.truth.z - HEIGHT) < HEIGHT_TOLERANCE
    assert "Ready to fly" in [text for _, module, text in cf.console.lines if module == "SUP"]
    cf.close()


def test_that_a_velocity_setpoint_moves_the_mav_and_the_estimate_follows():
    # Fixture
    cf = firmware_cf(seed=3)
    # Test: 0.5 m/s forward for 2 s after climbing
    pilot(cf, 8000, lambda t: (lambda sp: hover(sp, vx=0.5 if 6000 <= t < 8000 else 0.0)))
    # Assert: about 1 m, less the velocity loop's lag
    truth, estimate = cf.model.truth, cf.model.estimate
    assert PULSE_DISTANCE_M[0] < truth.x < PULSE_DISTANCE_M[1]
    assert abs(truth.y) < DRIFT_TOLERANCE_M
    assert math.hypot(estimate.x - truth.x, estimate.y - truth.y) < ESTIMATE_TOLERANCE_M
    cf.close()


def test_that_the_firmware_watchdog_levels_out_and_then_locks_when_setpoints_stop():
    # Fixture
    cf = firmware_cf()
    # Test: setpoints stop at 6 s, in the air
    pilot(cf, 9000, lambda t: hover if t < 6000 else None)
    # Assert: COMMANDER_WDT_TIMEOUT_STABILIZE (500 ms), then _SHUTDOWN (2 s): supervisor.c's own rule, checked
    # at its 25 Hz rate
    entered = dict((state, tick) for tick, state in reversed(cf.supervisor.events))
    assert WARNING_LEVEL_OUT in entered and LOCKED in entered
    assert 6500 < entered[WARNING_LEVEL_OUT] <= 6500 + SUPERVISOR_PERIOD_MS
    assert 8000 < entered[LOCKED] <= 8000 + SUPERVISOR_PERIOD_MS
    assert cf.supervisor.watchdog_events
    cf.close()


LAND_FINAL_M = 0.15  # Navigation.c's last landing height (app.landFinal)
LAND_STEP_MS = 3000


def landing(ramp):
    """Hover at 1 m, 3 s at landFinal, then (``ramp``) 3 s down to the ground, then motors off."""
    def setpoint_at(t):
        if t < 6000:
            return hover
        if t < 9000:
            return lambda sp: hover(sp, z=LAND_FINAL_M)
        if ramp and t < 12000:
            return lambda sp: hover(sp, z=LAND_FINAL_M * (1.0 - (t - 9000) / LAND_STEP_MS))
        return lambda sp: (sp.memset_zero(), sp)[1]
    return setpoint_at


def test_that_cutting_the_motors_at_the_last_landing_height_is_a_landing():
    # Fixture
    cf = firmware_cf()
    # Test: Navigation.c's landing (and cflib's MotionCommander's): the motors stop a few cm up, here 0.15 m
    pilot(cf, 11000, landing(ramp=False))
    # Assert: the MAV falls 0.15 m and hits the ground at ~1.7 m/s: a Crazyflie lands like that every day
    assert not cf.model.crashed
    assert cf.model.truth.z == 0.0
    cf.close()


def test_that_cutting_the_motors_at_a_metre_is_a_crash():
    # Fixture
    cf = firmware_cf()
    # Test: hover at 1 m, then motors off
    pilot(cf, 8000, lambda t: hover if t < 6000 else (lambda sp: (sp.memset_zero(), sp)[1]))
    # Assert: a 1 m fall hits the ground at ~4.4 m/s, past the 2.5 m/s (0.32 m fall) the crash rule allows
    assert cf.model.crashed
    assert "ground" in cf.model.crash_reason
    cf.close()


def test_that_the_apps_landing_ramp_touches_down_gently():
    # Fixture
    cf = firmware_cf()
    # Test: the app's landing (vertical.landing_setpoint): from 0.15 m down to the ground, then motors off
    pilot(cf, 14000, landing(ramp=True))
    # Assert
    assert not cf.model.crashed
    assert cf.model.truth.z == 0.0
    cf.close()


def test_that_the_same_seed_flies_the_same_and_a_second_boot_starts_afresh():
    # Fixture: two boots in one process; the first leaves its firmware armed and flying
    first = firmware_cf(seed=7)
    pilot(first, 7000, lambda t: hover)
    second = firmware_cf(seed=7)
    # Test
    pilot(second, 7000, lambda t: hover)
    # Assert: nothing of the first firmware's statics leaked into the second (each boot loads its own copy)
    assert first.model.truth.as_tuple() == second.model.truth.as_tuple()
    assert first.model.estimate.as_tuple() == second.model.estimate.as_tuple()
    assert first.supervisor.events == second.supervisor.events
    first.close()
    second.close()


def test_that_another_seed_draws_other_sensor_noise():
    # Fixture
    a, b = firmware_cf(seed=1), firmware_cf(seed=2)
    # Test
    pilot(a, 6000, lambda t: hover)
    pilot(b, 6000, lambda t: hover)
    # Assert
    assert a.model.truth.as_tuple() != b.model.truth.as_tuple()
    a.close()
    b.close()


@pytest.mark.parametrize("positioning, loco_ranges", [("uwb", True), ("flow", False)])
def test_that_the_loco_deck_ranges_only_when_it_positions(positioning, loco_ranges):
    # Fixture
    cf = firmware_cf(positioning=positioning)
    # Test
    pilot(cf, 5000, lambda t: hover)
    # Assert
    status = cf.model.stack.status
    assert (status.uwb_updates > 0) == loco_ranges
    assert status.flow_updates > 0 and status.tof_updates > 0
    cf.close()


def test_that_featureless_ground_costs_the_flow_deck_its_measurements():
    # Fixture
    textured, featureless = firmware_cf(), firmware_cf(ground_texture=0.1)
    # Test
    pilot(textured, 6000, lambda t: hover)
    pilot(featureless, 6000, lambda t: hover)
    # Assert: the PMW3901 reports no motion on most frames over low texture
    assert featureless.model.stack.status.flow_updates < 0.5 * textured.model.stack.status.flow_updates
    textured.close()
    featureless.close()


def test_that_nlos_ranges_are_dropped_by_the_twr_outlier_filter():
    # Fixture: a few ranges long by up to 2 m (lpsTwrTag.c's filter keeps those within 4 sigma of the history)
    clean, nlos = firmware_cf(uwb_nlos_probability=0.0), firmware_cf(uwb_nlos_probability=0.05, uwb_nlos_max_m=2.0)
    # Test
    pilot(clean, 8000, lambda t: hover)
    pilot(nlos, 8000, lambda t: hover)
    # Assert: of the ~40 long ranges the filter drops the longest (both drop the first ranges of each anchor,
    # while its history fills); the estimate still holds
    assert nlos.model.stack.status.uwb_rejected - clean.model.stack.status.uwb_rejected >= MIN_NLOS_DROPPED
    assert math.hypot(nlos.model.estimate.x - nlos.model.truth.x,
                      nlos.model.estimate.y - nlos.model.truth.y) < ESTIMATE_TOLERANCE_M
    clean.close()
    nlos.close()


def test_that_the_battery_and_motors_are_logged_as_on_a_crazyflie():
    # Fixture
    cf = firmware_cf()
    # Test
    pilot(cf, 5000, lambda t: hover)
    # Assert: pm.vbat sags under load, motor.m1-m4 carry the PWM the stabilizer set (hover near thrustBase)
    vbat = cf.log_get_float(cf.log_get_var_id("pm", "vbat"))
    motors = [cf.log_get_uint(cf.log_get_var_id("motor", "m%d" % i)) for i in range(1, 5)]
    assert 7.0 < vbat < FirmwarePlantConfig().battery_full_v
    assert all(25000 < m < 45000 for m in motors)
    cf.close()


def test_that_a_flip_is_a_crash():
    # Fixture
    cf = firmware_cf()

    def flip(sp):
        sp.memset_zero()
        sp.mode.roll = sp.mode.pitch = sp.mode.yaw = modeAbs  # attitude setpoint, thrust by hand
        sp.attitude.roll = 150.0
        sp.thrust = 40000
        return sp
    # Test: hover at 1 m, then ask for a 150 degree roll
    pilot(cf, 7000, lambda t: hover if t < 6000 else flip)
    # Assert: past 90 degrees of tilt the MAV has tumbled, a crash whatever its speed
    assert cf.model.crashed
    assert "tumbled" in cf.model.crash_reason
    cf.close()
