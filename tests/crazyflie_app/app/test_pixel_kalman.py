"""The constant-velocity pixel Kalman filter: convergence, missed updates, time base, covariance health."""
import numpy as np
import pytest

from crazyflie_app.app.pixel_kalman import PixelKalmanFilter

SEED = 7
POSITION_TOLERANCE_PX = 1.5
VELOCITY_TOLERANCE_PXS = 3.0
TICK_S = 0.01


def assert_covariance_healthy(P):
    assert np.allclose(P, P.T, atol=1e-9)
    assert np.all(np.linalg.eigvalsh(P) > 0)


def test_that_it_converges_on_a_constant_velocity_target():
    # Fixture: a target moving at (20, -10) px/s, measured every 0.1 s with 3 px noise
    rng = np.random.RandomState(SEED)
    sut = PixelKalmanFilter(100.0, 100.0, measurement_std_px=3.0)
    velocity = np.array([20.0, -10.0])
    truth = np.array([100.0, 100.0])
    # Test: 5 s of 10 ms ticks
    for tick in range(1, 501):
        sut.predict(TICK_S)
        truth = truth + velocity * TICK_S
        if tick % 10 == 0:
            sut.update(*(truth + rng.normal(0, 3.0, 2)))
        assert_covariance_healthy(sut.P)
    # Assert
    assert np.allclose(sut.position, truth, atol=POSITION_TOLERANCE_PX)
    assert np.allclose(sut.velocity, velocity, atol=VELOCITY_TOLERANCE_PXS)


def test_that_it_survives_missed_updates_and_reconverges():
    rng = np.random.RandomState(SEED)
    sut = PixelKalmanFilter(0.0, 0.0, accel_psd=20.0)  # a steady target: low process noise
    truth, velocity = np.zeros(2), np.array([15.0, 5.0])
    for tick in range(1, 301):
        sut.predict(TICK_S)
        truth = truth + velocity * TICK_S
        if tick % 10 == 0:
            sut.update(*(truth + rng.normal(0, 2.0, 2)))
    settled_var = sut.P[0, 0]
    # one second without detections: the prediction keeps moving and the uncertainty grows
    for _ in range(100):
        sut.predict(TICK_S)
        truth = truth + velocity * TICK_S
        assert_covariance_healthy(sut.P)
    assert sut.P[0, 0] > 2 * settled_var
    assert np.allclose(sut.position, truth, atol=3 * POSITION_TOLERANCE_PX)
    for tick in range(1, 101):
        sut.predict(TICK_S)
        truth = truth + velocity * TICK_S
        if tick % 10 == 0:
            sut.update(*(truth + rng.normal(0, 2.0, 2)))
    assert np.allclose(sut.position, truth, atol=POSITION_TOLERANCE_PX)


def test_that_prediction_runs_in_real_seconds_whatever_the_tick_split():
    # The C app predicted with dt = 0.001 per 10 ms loop; here dt is the real duration in seconds, and the
    # white-acceleration model composes exactly: two 5 ms predictions equal one 10 ms prediction.
    a, b = PixelKalmanFilter(10.0, 20.0), PixelKalmanFilter(10.0, 20.0)
    for sut in (a, b):
        sut.x[2:] = (30.0, -40.0)
    a.predict(0.010)
    b.predict(0.005)
    b.predict(0.005)
    assert a.position == pytest.approx((10.3, 19.6))
    assert np.allclose(a.x, b.x) and np.allclose(a.P, b.P)


def test_that_the_covariance_is_the_full_4x4_matrix_and_stays_symmetric():
    # The C filter stored P as float[2][2] and wrote P[2][2], P[3][3] out of bounds.
    sut = PixelKalmanFilter(0.0, 0.0, measurement_std_px=0.01, accel_psd=1e6)
    assert sut.P.shape == (4, 4)
    for _ in range(200):
        sut.predict(0.05)
        sut.update(1e3, -1e3)
        assert_covariance_healthy(sut.P)
    assert sut.P[2, 2] > 0 and sut.P[3, 3] > 0 and sut.P[0, 2] != 0


def test_that_negative_time_steps_are_refused():
    with pytest.raises(ValueError):
        PixelKalmanFilter(0, 0).predict(-0.01)
