"""The firmware emulation: scheduler, commander priorities, supervisor watchdog, log/param, MAV model."""
import math

import pytest

from crazyflie_app.firmware import (COMMANDER_PRIORITY_CRTP, COMMANDER_PRIORITY_EXTRX,
                                    COMMANDER_PRIORITY_HIGHLEVEL, Crazyflie, FirmwareAssertError,
                                    LOG_VARID_INVALID, MavModelConfig, PARAM_VARID_INVALID, PORT_MAX_DELAY,
                                    modeAbs, setpoint_t, v_task_delay)
from crazyflie_app.firmware.freertos import Scheduler
from crazyflie_app.firmware.reduced.mav_model import MavModel
from crazyflie_app.firmware.supervisor import FLYING, LANDED, LOCKED, WARNING_LEVEL_OUT

from .conftest import HEIGHT, HEIGHT_TOLERANCE, hover



def armed_crazyflie(**kwargs):
    """A Bolt (arming required) whose client armed it, as the app does after its checks."""
    cf = Crazyflie(**kwargs)
    assert cf.supervisor_request_arming(True)
    return cf


def streaming_app(cf, stop_after_ms=None, period=10, vx=0.0):
    """A task that streams hover setpoints, optionally stalling (no more setpoints) after stop_after_ms."""
    sp = setpoint_t()
    while stop_after_ms is None or cf.x_task_get_tick_count() < stop_after_ms:
        cf.commander_set_setpoint(hover(sp, vx=vx), COMMANDER_PRIORITY_EXTRX)
        yield v_task_delay(period)
    yield v_task_delay(PORT_MAX_DELAY)


# -- scheduler ------------------------------------------------------------------------------------------------

def test_that_tasks_wake_after_relative_delays_in_tick_order():
    # Fixture
    sut = Scheduler()
    log = []

    def task(name, period):
        while True:
            log.append((sut.x_task_get_tick_count(), name))
            yield v_task_delay(period)

    sut.x_task_create(task("a", 10), "a", 1)
    sut.x_task_create(task("b", 15), "b", 1)
    # Test
    sut.run_until(31)
    # Assert
    assert log == [(0, "a"), (0, "b"), (10, "a"), (15, "b"), (20, "a"), (30, "a"), (30, "b")]
    assert sut.x_task_get_tick_count() == 31


def test_that_tasks_due_on_the_same_tick_run_by_priority():
    sut = Scheduler()
    order = []

    def task(name):
        order.append(name)
        yield v_task_delay(PORT_MAX_DELAY)

    sut.x_task_create(task("low"), "low", 1)
    sut.x_task_create(task("high"), "high", 5)
    sut.run_until(1)
    assert order == ["high", "low"]


def test_that_a_parked_task_leaves_the_ready_list():
    sut = Scheduler()

    def task():
        yield v_task_delay(PORT_MAX_DELAY)

    sut.x_task_create(task(), "parked", 1)
    sut.run_until(5)
    assert sut.task_names() == []


# -- commander --------------------------------------------------------------------------------------------------

def test_that_lower_priority_setpoints_are_rejected_until_the_priority_is_relaxed():
    cf = Crazyflie()
    app_sp, radio_sp = hover(setpoint_t(), vx=0.1), hover(setpoint_t(), vx=-0.1)
    assert cf.commander_set_setpoint(app_sp, COMMANDER_PRIORITY_EXTRX)
    assert not cf.commander_set_setpoint(radio_sp, COMMANDER_PRIORITY_CRTP)
    assert not cf.commander_set_setpoint(radio_sp, COMMANDER_PRIORITY_HIGHLEVEL)
    assert cf.commander.commander_get_setpoint().velocity.x == 0.1
    cf.commander_relax_priority()
    assert cf.commander_set_setpoint(radio_sp, COMMANDER_PRIORITY_CRTP)
    assert cf.commander.commander_get_setpoint().velocity.x == -0.1
    assert cf.commander.rejected == 2


def test_that_an_accepted_setpoint_is_stamped_and_copied():
    cf = Crazyflie()
    cf.run_until(1234)
    sp = hover(setpoint_t(), vx=0.05)
    cf.commander_set_setpoint(sp, COMMANDER_PRIORITY_EXTRX)
    sp.velocity.x = 9.0  # the caller reuses its struct: the queued copy must not change
    assert sp.timestamp == 1234
    assert cf.commander.commander_get_setpoint().velocity.x == 0.05
    cf.run_until(1300)
    assert cf.commander_get_inactivity_time() == 1300 - 1234


# -- supervisor watchdog ------------------------------------------------------------------------------------------

def test_that_a_stalled_app_levels_out_after_500_ms_and_recovers_when_setpoints_resume():
    # Fixture: stream for 3 s, stall 1 s (> 500 ms, < 2 s), stream again
    cf = armed_crazyflie()
    sp = setpoint_t()

    def app():
        for phase_end, streaming in ((3000, True), (4000, False), (6000, True)):
            while cf.x_task_get_tick_count() < phase_end:
                if streaming:
                    cf.commander_set_setpoint(hover(sp, vx=0.3), COMMANDER_PRIORITY_EXTRX)
                yield v_task_delay(10)
        yield v_task_delay(PORT_MAX_DELAY)

    cf.x_task_create(app(), "APP", 1)
    # Test
    cf.run_until(6000)
    # Assert: last setpoint at tick 2990 -> level-out on tick 2990 + 501 exactly; flying again on the first
    # stabilizer step (10 ms period) after the stream resumes at 4000
    states = cf.supervisor.events
    assert (3491, WARNING_LEVEL_OUT) in states
    assert [t for t, s in states if s == FLYING and t > 3491] == [4001]
    assert cf.supervisor.state == FLYING
    assert abs(cf.model.truth.z - HEIGHT) < HEIGHT_TOLERANCE


def test_that_level_out_keeps_height_and_lets_horizontal_speed_decay():
    cf = armed_crazyflie()
    cf.x_task_create(streaming_app(cf, stop_after_ms=3000, vx=0.3), "APP", 1)
    cf.run_until(3000)
    speed_before = cf.model.truth.vx
    cf.run_until(4000)  # level-out from 3491
    assert cf.supervisor.state == WARNING_LEVEL_OUT
    assert 0.0 < cf.model.truth.vx < speed_before
    assert abs(cf.model.truth.z - HEIGHT) < HEIGHT_TOLERANCE


def test_that_a_stall_longer_than_2_s_locks_the_motors_for_good():
    cf = armed_crazyflie()
    cf.x_task_create(streaming_app(cf, stop_after_ms=3000), "APP", 1)
    cf.run_until(6000)
    assert (2990 + 2001, LOCKED) in cf.supervisor.events
    assert cf.model.truth.z == 0.0  # fell
    # sticky: fresh setpoints do not unlock
    cf.commander_set_setpoint(hover(setpoint_t()), COMMANDER_PRIORITY_EXTRX)
    cf.run_until(6500)
    assert cf.supervisor.state == LOCKED
    assert cf.model.truth.z == 0.0


def test_that_streaming_null_setpoints_lands_without_a_watchdog_event():
    cf = armed_crazyflie()
    sp = setpoint_t()

    def app():
        while cf.x_task_get_tick_count() < 3000:
            cf.commander_set_setpoint(hover(sp, z=0.15), COMMANDER_PRIORITY_EXTRX)
            yield v_task_delay(10)
        while True:
            sp.memset_zero()
            cf.commander_set_setpoint(sp, COMMANDER_PRIORITY_EXTRX)
            yield v_task_delay(10)

    cf.x_task_create(app(), "APP", 1)
    cf.run_until(8000)
    assert cf.supervisor.state == LANDED
    assert cf.supervisor.watchdog_events == []
    assert cf.model.truth.z == 0.0


# -- log / param ---------------------------------------------------------------------------------------------------

def test_that_log_ids_resolve_by_group_and_name_and_unknown_names_are_invalid():
    cf = Crazyflie(start=(1.5, -0.5, 0.0), model_config=MavModelConfig(position_noise_m=0.0,
                                                                         position_bias_m=0.0))
    ids = [cf.log_get_var_id("stateEstimate", n) for n in ("x", "y", "z", "vx", "vy")]
    assert len(set(ids)) == 5 and LOG_VARID_INVALID not in ids
    assert cf.log_get_float(ids[0]) == pytest.approx(1.5)
    assert cf.log_get_float(ids[1]) == pytest.approx(-0.5)
    assert cf.log_get_var_id("stateEstimate", "nope") == LOG_VARID_INVALID
    with pytest.raises(FirmwareAssertError):
        cf.log_get_float(LOG_VARID_INVALID)
    with pytest.raises(KeyError, match="stateEstimate.nope"):
        cf.registry.log_read("stateEstimate.nope")


def test_that_deck_params_are_read_only_uints_and_reflect_the_decks_fitted():
    cf = Crazyflie(decks=("bcFlow2",))
    flow, loco = cf.param_get_var_id("deck", "bcFlow2"), cf.param_get_var_id("deck", "bcLoco")
    assert cf.param_get_uint(flow) == 1 and cf.param_get_uint(loco) == 0
    assert cf.param_get_var_id("deck", "bcAI").id == PARAM_VARID_INVALID
    with pytest.raises(FirmwareAssertError, match="read-only"):
        cf.registry.param_set_int(flow, 0)
    with pytest.raises(FirmwareAssertError, match="paramGetFloat"):
        cf.param_get_float(flow)
    with pytest.raises(FirmwareAssertError):
        cf.param_get_uint(cf.param_get_var_id("deck", "bcAI"))


# -- MAV model -------------------------------------------------------------------------------------------------------

TAU_TOLERANCE = 0.05


def quiet(**kw):
    return MavModelConfig(position_noise_m=0.0, position_bias_m=0.0, height_noise_m=0.0, velocity_noise_mps=0.0,
                          **kw)


def test_that_the_velocity_response_has_the_configured_time_constant():
    model = MavModel(quiet(velocity_tau_s=0.3), start=(0, 0, 1.0))
    sp = hover(setpoint_t(), vx=0.1)
    for _ in range(30):  # 0.3 s
        model.step(0.01, sp, True)
    assert model.truth.vx / 0.1 == pytest.approx(1 - math.exp(-1), abs=TAU_TOLERANCE)


def test_that_tilt_limits_the_acceleration_and_speed_is_capped():
    model = MavModel(quiet(max_speed_mps=1.1), start=(0, 0, 1.0))
    sp = hover(setpoint_t(), vx=5.0)
    model.step(0.01, sp, True)
    assert model.truth.vx <= 9.81 * math.tan(math.radians(20)) * 0.01 + 1e-9
    for _ in range(500):
        model.step(0.01, sp, True)
    assert model.truth.vx == pytest.approx(1.1, abs=0.01)


def test_that_position_mode_converges_on_the_estimate_so_a_bias_becomes_a_true_offset():
    model = MavModel(MavModelConfig(position_noise_m=0.0, position_bias_m=0.05, velocity_noise_mps=0.0), seed=3,
                     start=(0, 0, 1.0))
    sp = setpoint_t()
    sp.mode.x = sp.mode.y = sp.mode.z = modeAbs
    sp.position.x, sp.position.y, sp.position.z = 1.0, 0.5, 1.0
    for _ in range(1500):
        model.step(0.01, sp, True)
    assert model.estimate.x == pytest.approx(1.0, abs=0.005)
    assert model.truth.x == pytest.approx(1.0 - model._bias_x, abs=0.005)
    assert abs(model._bias_x) > 0.001


def test_that_the_flow_estimate_drifts_with_distance_and_runs_are_seeded():
    def fly(seed):
        model = MavModel(MavModelConfig(estimator="flow", position_noise_m=0.0, flow_drift_per_m=0.05), seed=seed,
                         start=(0, 0, 1.0))
        sp = hover(setpoint_t(), vx=0.5)
        for _ in range(1000):
            model.step(0.01, sp, True)
        return model.estimate.x - model.truth.x, model.estimate.y - model.truth.y

    assert fly(1) == fly(1)
    assert fly(1) != fly(2)
    assert max(abs(e) for e in fly(1)) > 0.005


def test_that_wind_gusts_push_the_mav_off_a_hover():
    model = MavModel(quiet(wind_gust_mps2=1.0), seed=4, start=(0, 0, 1.0))
    sp = hover(setpoint_t())
    excursion = 0.0
    for _ in range(2000):
        model.step(0.01, sp, True)
        excursion = max(excursion, math.hypot(model.truth.x, model.truth.y))
    assert excursion > 0.01
