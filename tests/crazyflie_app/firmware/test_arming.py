"""The emulated Bolt requires arming (CONFIG_MOTORS_REQUIRE_ARMING): unarmed it goes nowhere, armed it flies,
and the firmware's disarm timeouts apply (30 s armed on the ground, 3 s landed)."""
import pytest

from crazyflie_app.firmware import COMMANDER_PRIORITY_EXTRX, PORT_MAX_DELAY, Crazyflie, setpoint_t, v_task_delay
from crazyflie_app.firmware.supervisor import (FLYING, LANDED, LANDING_TIMEOUT_MS, LOCKED, PRE_FLIGHT,
                                               PREFLIGHT_TIMEOUT_MS, READY_TO_FLY)

from .conftest import HEIGHT, HEIGHT_TOLERANCE, hover



def hover_app(cf, arm_at_ms=None, start_ms=0, stop_ms=None, land_ms=None):
    """Streams hover setpoints from start_ms (null setpoints from land_ms, nothing from stop_ms); requests
    arming at arm_at_ms (None: never, like an app written for the auto-arming CF2)."""
    sp = setpoint_t()
    while stop_ms is None or cf.x_task_get_tick_count() < stop_ms:
        now = cf.x_task_get_tick_count()
        if arm_at_ms is not None and now >= arm_at_ms:
            cf.supervisor_request_arming(True)
            arm_at_ms = None
        if now >= start_ms:
            if land_ms is not None and now >= land_ms:
                sp.memset_zero()
            else:
                hover(sp)
            cf.commander_set_setpoint(sp, COMMANDER_PRIORITY_EXTRX)
        yield v_task_delay(10)
    yield v_task_delay(PORT_MAX_DELAY)


def test_that_an_unarmed_bolt_whose_app_does_not_request_arming_goes_nowhere():
    cf = Crazyflie()
    cf.x_task_create(hover_app(cf), "APP", 1)
    cf.run_until(10000)
    assert cf.model.truth.z == 0.0
    assert cf.supervisor.state == PRE_FLIGHT and not cf.supervisor_is_armed()
    assert cf.commander.commander_get_setpoint().position.z == HEIGHT  # the app did command, to no effect


def test_that_the_same_app_flies_once_it_requests_arming():
    cf = Crazyflie()
    cf.x_task_create(hover_app(cf, arm_at_ms=1000), "APP", 1)
    cf.run_until(10000)
    assert cf.model.truth.z == pytest.approx(HEIGHT, abs=HEIGHT_TOLERANCE)
    assert [s for _, s in cf.supervisor.events][:2] == [READY_TO_FLY, FLYING]
    assert any(text == "Ready to fly" for _, _, text in cf.console.lines)


def test_that_the_cf2_auto_arms_without_a_request():
    cf = Crazyflie(require_arming=False)
    cf.x_task_create(hover_app(cf), "APP", 1)
    cf.run_until(10000)
    assert cf.model.truth.z == pytest.approx(HEIGHT, abs=HEIGHT_TOLERANCE)


def test_that_arming_is_refused_when_the_supervisor_is_locked():
    cf = Crazyflie()
    cf.x_task_create(hover_app(cf, arm_at_ms=0, stop_ms=3000), "APP", 1)
    cf.run_until(6000)  # setpoints stop at 3 s: level-out, then locked
    assert cf.supervisor.state == LOCKED
    assert not cf.supervisor_is_armed()
    assert not cf.supervisor_request_arming(True)


def test_that_an_armed_bolt_left_on_the_ground_disarms_after_the_preflight_timeout():
    # Fixture: armed at 1 s, the first setpoint only after the 30 s pre-flight timeout
    cf = Crazyflie()
    cf.x_task_create(hover_app(cf, arm_at_ms=1000, start_ms=1000 + PREFLIGHT_TIMEOUT_MS + 500), "APP", 1)
    # Test
    cf.run_until(1000 + PREFLIGHT_TIMEOUT_MS + 6000)
    # Assert: disarmed on the tick after the timeout (counted from READY_TO_FLY, on the stabilizer tick after
    # the request), and the late setpoints lift nothing
    ready_at = [t for t, s in cf.supervisor.events if s == READY_TO_FLY][0]
    assert ready_at == 1010
    assert (ready_at + PREFLIGHT_TIMEOUT_MS + 1, PRE_FLIGHT) in cf.supervisor.events
    assert not cf.supervisor_is_armed()
    assert cf.model.truth.z == 0.0
    assert any(text == "Disarming" for _, _, text in cf.console.lines)


def test_that_a_bolt_landed_for_3_s_disarms_and_does_not_take_off_again():
    # Fixture: fly, land with null setpoints from 6 s, command a hover again at 14 s (landed at ~8 s)
    cf = Crazyflie()
    sp = setpoint_t()

    def app():
        cf.supervisor_request_arming(True)
        while True:
            now = cf.x_task_get_tick_count()
            if 6000 <= now < 14000:
                sp.memset_zero()
            else:
                hover(sp)
            cf.commander_set_setpoint(sp, COMMANDER_PRIORITY_EXTRX)
            yield v_task_delay(10)

    cf.x_task_create(app(), "APP", 1)
    # Test
    cf.run_until(20000)
    # Assert
    landed_at = [t for t, s in cf.supervisor.events if s == LANDED][0]
    assert (landed_at + LANDING_TIMEOUT_MS + 1, PRE_FLIGHT) in cf.supervisor.events
    assert cf.supervisor.state == PRE_FLIGHT and not cf.supervisor_is_armed()
    assert cf.model.truth.z == 0.0
    assert cf.supervisor.watchdog_events == []


def test_that_disarming_in_flight_cuts_the_motors():
    cf = Crazyflie()
    cf.x_task_create(hover_app(cf, arm_at_ms=0), "APP", 2)

    def disarm():
        yield v_task_delay(6000)
        cf.supervisor_request_arming(False)
        yield v_task_delay(PORT_MAX_DELAY)

    cf.x_task_create(disarm(), "CLIENT", 1)
    cf.run_until(6000)
    assert cf.model.truth.z > 0.5
    cf.run_until(9000)
    assert cf.model.truth.z == 0.0
    assert cf.supervisor.state == PRE_FLIGHT
