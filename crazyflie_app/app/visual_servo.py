"""Visual servo of the navigation core: the target's pixel track, the servo law and the reached rule.

* APPROACH: a constant-velocity Kalman filter tracks the target's image position, predicted every tick with
  the tick's real duration; detections (corrected for the MAV's motion since capture) update it. The
  visual-servo law commands a body velocity proportional to the metric image offset (``servoGain``),
  saturated at ``approachSpeed``; an integral term (``servoKi``) acts only when a disturbance holds the MAV
  near but off the centre (inside 3 settle radii and slower than ``settleSpeed``), so calm approaches stay
  monotonic.
* The reached rule: ``captureRadius`` (tau = 40 px, the paper's threshold) marks the tree as captured; the
  paper's rule alone would stop ~0.15 m off centre, so the tree is declared *reached* only once the
  filtered offset stays below ``settleRadius`` with the MAV slower than ``settleSpeed`` for ``settleDwell``
  (default 6 px ~ 2.3 cm at 1.25 m, 0.02 m/s, held 0.6 s), which keeps the mean deviation at a few mm
  with an ideal camera. So that wind cannot stall the mission, from ``settleGrace`` (8 s) after the first
  capture both thresholds grow by ``settleRelax`` (1 px/s) up to tau: the deviation degrades gracefully
  instead.
"""
import math

from crazyflie_app.app.camera_geometry import CameraGeometry
from crazyflie_app.app.nav_types import NavigationParams, Pose
from crazyflie_app.app.pixel_kalman import PixelKalmanFilter


def servo_velocity(offset_fwd_m: float, offset_left_m: float, gain: float, max_speed: float,
                   integral: tuple[float, float] = (0.0, 0.0), integral_gain: float = 0.0) -> tuple[float, float]:
    """Visual-servo law: body velocity towards the target, proportional to its metric image offset (plus an
    optional integral term) and saturated (direction kept) at ``max_speed``."""
    vx = gain * offset_fwd_m + integral_gain * integral[0]
    vy = gain * offset_left_m + integral_gain * integral[1]
    speed = math.hypot(vx, vy)
    if speed > max_speed > 0:
        vx, vy = vx * max_speed / speed, vy * max_speed / speed
    return vx, vy


class VisualServo:
    """The pixel filter of the target and the servo / reached state of one approach."""

    def __init__(self, params: NavigationParams, geometry: CameraGeometry):
        self.params = params
        self.geometry = geometry  # a CameraGeometry
        self.filter = None  # PixelKalmanFilter while tracking
        self.pixel_error = (0.0, 0.0)
        self.captured = False
        self._filter_t_ms = 0
        self._settle_since = None
        self._captured_since = None
        self._integral = (0.0, 0.0)

    def start(self, t_ms: int, u: float, v: float) -> None:
        """Track a target first seen (now) at pixel (u, v)."""
        p = self.params
        self.filter = PixelKalmanFilter(u, v, p.kf_measurement_std_px, p.kf_accel_psd)
        self._filter_t_ms = t_ms
        self._settle_since = None
        self._captured_since = None
        self._integral = (0.0, 0.0)

    def lose(self) -> None:
        """Stop tracking (recovery): the filter is gone."""
        self.filter = None

    def drop(self) -> None:
        """The target is done or gone."""
        self.filter = None
        self.captured = False

    def predict(self, t_ms: int) -> None:
        if t_ms > self._filter_t_ms:
            self.filter.predict((t_ms - self._filter_t_ms) / 1000.0)  # real time, in seconds
            self._filter_t_ms = t_ms

    def measure(self, t_ms: int, u: float, v: float) -> None:
        """A detection of the target (ego-corrected pixel); ignored when not tracking."""
        if self.filter is None:
            return
        self.predict(t_ms)
        self.filter.update(u, v)

    def step(self, t_ms: int, pose: Pose, last_tick_ms: int) -> tuple[float, float] | None:
        """One tick of the approach (after ``predict``): None when the reached rule holds, else the body
        velocity (vx, vy) of the servo law."""
        p = self.params
        u, v = self.filter.position
        eu, ev = self.geometry.centre_error(u, v)
        self.pixel_error = (eu, ev)
        error_px = math.hypot(eu, ev)
        self.captured = error_px < p.capture_radius_px  # the paper's tau: nearly centred
        # the relax clock runs from the first capture of this approach: a gust, or a hover jittering on the
        # real firmware, that pushes the target past tau for a moment must not start it over
        if self.captured and self._captured_since is None:
            self._captured_since = t_ms
        radius, speed = self.settle_thresholds(t_ms)
        if self.captured and error_px < radius and math.hypot(pose.vx, pose.vy) < speed:
            if self._settle_since is None:
                self._settle_since = t_ms
            if t_ms - self._settle_since >= p.settle_dwell_ms:
                return None
        else:
            self._settle_since = None
        offset = self.geometry.metric_offset(eu, ev, pose.z)  # metres forward, left
        self._integrate(t_ms, last_tick_ms, offset, error_px, math.hypot(pose.vx, pose.vy))
        return servo_velocity(offset[0], offset[1], p.servo_gain, p.approach_speed, self._integral,
                              p.servo_integral)

    def settle_thresholds(self, t_ms: int) -> tuple[float, float]:
        """(radius px, speed m/s) of the reached rule, relaxed by ``settle_relax`` per second captured."""
        p = self.params
        if self._captured_since is None:
            return p.settle_radius_px, p.settle_speed
        relax_s = max(0.0, (t_ms - self._captured_since - p.settle_grace_ms) / 1000.0)
        radius = min(p.settle_radius_px + p.settle_relax * relax_s, p.capture_radius_px)
        return radius, p.settle_speed * radius / max(p.settle_radius_px, 1e-9)

    def _integrate(self, t_ms, last_tick_ms, offset, error_px, speed):
        """Integral of the metric offset, only when a disturbance holds the MAV off the centre: close to it
        (within ``servo_integral_band`` settle radii) yet slower than ``settle_speed``. While the MAV closes
        in nothing is integrated, so a calm approach stays monotonic. Bounded so the integral term alone
        never exceeds half the approach speed."""
        p = self.params
        if error_px > p.servo_integral_band * p.settle_radius_px or p.servo_integral <= 0.0:
            self._integral = (0.0, 0.0)
            return
        if speed >= p.settle_speed:
            return  # still moving: hold the integral
        dt = 0.0 if last_tick_ms is None else max(0.0, (t_ms - last_tick_ms) / 1000.0)
        ix, iy = self._integral[0] + offset[0] * dt, self._integral[1] + offset[1] * dt
        limit = 0.5 * p.approach_speed / p.servo_integral
        norm = math.hypot(ix, iy)
        if norm > limit:
            ix, iy = ix * limit / norm, iy * limit / norm
        self._integral = (ix, iy)
