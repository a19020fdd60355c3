"""A reduced closed-loop model of a Crazyflie/Bolt quadrotor and its state estimate (stabilizer + estimator).

What the app sees of the real stack, reduced to what matters for 2-D navigation at 1-1.5 m
(``crazyflie.md`` section 5.2; gains from position_controller_pid.c):

* position axes in ``modeAbs``: velocity target = POSITION_KP * (setpoint - *estimate*), clamped to
  POSITION_VEL_MAX per axis in the yaw frame (so estimate errors become true position errors);
* velocity axes: world or body (``velocity_body``) frame targets;
* the velocity loop: a first-order response with time constant ``velocity_tau_s`` (~0.3 s), acceleration
  limited by the 20 degree tilt limit (g * tan 20 deg ~ 3.6 m/s^2); it regulates the *estimated* velocity;
* height: z in ``modeAbs`` is a PI on the estimated height (Kp 2.0, Ki 0.5), vertical lag ``vertical_tau_s``;
* yaw follows ``attitude.yaw`` (modeAbs) or integrates ``attitudeRate.yaw`` (modeVelocity);
* level-out (supervisor override, x/y disabled): horizontal velocity decays only through drag (``drag_tau_s``);
* motors off: free fall to the ground, then rest.

The estimate is truth + noise + bias, all seeded: ``uwb`` (Loco-like absolute position: white noise plus a
constant per-run bias) or ``flow`` (Flow-deck dead reckoning: unbiased at start, then a random-walk drift that
grows with the distance flown). Optional wind gusts are an Ornstein-Uhlenbeck acceleration disturbance.
"""
import math
import random
from dataclasses import dataclass

from crazyflie_app.firmware.commander import setpoint_t

GRAVITY = 9.81
POSITION_KP = 2.0  # 1/s, PID_POS_X_KP
POSITION_VEL_MAX = 1.1  # m/s, PID_POS_VEL_X_MAX * 1.1
Z_KP, Z_KI = 2.0, 0.5
Z_INTEGRATION_BAND_M = 0.1
Z_INTEGRAL_LIMIT = 0.1
TILT_MAX_DEG = 20.0  # PID_VEL_ROLL_MAX / PID_VEL_PITCH_MAX


@dataclass
class MavModelConfig:
    velocity_tau_s: float = 0.3
    vertical_tau_s: float = 0.25
    yaw_tau_s: float = 0.2
    drag_tau_s: float = 4.0
    max_speed_mps: float = 1.1  # horizontal speed envelope of the position/velocity loops
    tilt_max_deg: float = TILT_MAX_DEG
    # state estimate
    estimator: str = "uwb"  # "uwb" (absolute) or "flow" (drifting)
    position_noise_m: float = 0.01  # white noise per axis of stateEstimate.x/y
    position_bias_m: float = 0.02  # uwb: std of the constant per-run bias per axis
    flow_drift_per_m: float = 0.02  # flow: random-walk drift std per metre flown, per axis
    height_noise_m: float = 0.003  # ToF-like
    velocity_noise_mps: float = 0.005
    wind_gust_mps2: float = 0.0  # std of the gust acceleration (0 = still air)
    wind_tau_s: float = 2.0

    def validate(self) -> "MavModelConfig":
        if self.estimator not in ("uwb", "flow"):
            raise ValueError("estimator must be 'uwb' or 'flow', got %r" % self.estimator)
        for name in ("velocity_tau_s", "vertical_tau_s", "yaw_tau_s", "drag_tau_s", "wind_tau_s"):
            if getattr(self, name) <= 0:
                raise ValueError("%s must be positive" % name)
        return self


@dataclass(slots=True)
class State:
    """A pose and velocity (truth or estimate): m, m/s, yaw in degrees."""
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    vx: float = 0.0
    vy: float = 0.0
    vz: float = 0.0
    yaw: float = 0.0
    roll: float = 0.0  # the reduced model flies level
    pitch: float = 0.0

    def as_tuple(self) -> tuple[float, ...]:
        return (self.x, self.y, self.z, self.vx, self.vy, self.vz, self.yaw)


def _clamp(value: float, limit: float) -> float:
    return limit if value > limit else (-limit if value < -limit else value)


class MavModel:
    """Truth (``self.truth``) and estimate (``self.estimate``), stepped by the stabilizer task."""

    crashed = False  # the reduced model has no attitude to tumble on and lands at the controller's pace
    crash_reason = None

    def __init__(self, config: MavModelConfig | None = None, seed: int = 0,
                 start: tuple[float, float, float] = (0.0, 0.0, 0.0), start_yaw_deg: float = 0.0):
        self.config = (config or MavModelConfig()).validate()
        self._rng = random.Random(seed)
        self.truth = State(*start, yaw=start_yaw_deg)
        self.estimate = State(*start, yaw=start_yaw_deg)
        c = self.config
        self._bias_x = self._rng.gauss(0.0, c.position_bias_m) if c.estimator == "uwb" else 0.0
        self._bias_y = self._rng.gauss(0.0, c.position_bias_m) if c.estimator == "uwb" else 0.0
        self._z_integral = 0.0
        self._wind_ax = self._wind_ay = 0.0
        self._vx_err = self._vy_err = 0.0
        self.distance_flown_m = 0.0
        self._refresh_estimate()

    # -- controller (position_controller_pid.c, reduced) -----------------------------------------------

    def _horizontal_velocity_target(self, sp):
        """World-frame velocity target of the position/velocity loop, or None when x/y are disabled."""
        if sp.mode.x == 0 and sp.mode.y == 0:
            return None
        est, c = self.estimate, self.config
        yaw = math.radians(est.yaw)
        cos_y, sin_y = math.cos(yaw), math.sin(yaw)
        if sp.velocity_body:
            bvx, bvy = sp.velocity.x, sp.velocity.y
        else:
            bvx = sp.velocity.x * cos_y + sp.velocity.y * sin_y
            bvy = sp.velocity.y * cos_y - sp.velocity.x * sin_y
        if sp.mode.x == 1 or sp.mode.y == 1:
            ex, ey = sp.position.x - est.x, sp.position.y - est.y
            bex, bey = ex * cos_y + ey * sin_y, ey * cos_y - ex * sin_y
            if sp.mode.x == 1:
                bvx = _clamp(POSITION_KP * bex, POSITION_VEL_MAX)
            if sp.mode.y == 1:
                bvy = _clamp(POSITION_KP * bey, POSITION_VEL_MAX)
        bvx, bvy = _clamp(bvx, c.max_speed_mps), _clamp(bvy, c.max_speed_mps)
        return bvx * cos_y - bvy * sin_y, bvx * sin_y + bvy * cos_y

    def _vertical_velocity_target(self, sp, dt):
        if sp.mode.z == 1:
            error = sp.position.z - self.estimate.z
            # the firmware's integrator (Ki 0.5) compensates thrust/weight errors, which this model does not
            # have; integrating only near the setpoint keeps it from winding up during the climb
            if abs(error) < Z_INTEGRATION_BAND_M:
                self._z_integral = _clamp(self._z_integral + error * dt, Z_INTEGRAL_LIMIT)
            return _clamp(Z_KP * error + Z_KI * self._z_integral, POSITION_VEL_MAX)
        if sp.mode.z == 2:
            return sp.velocity.z
        return 0.0

    # -- plant -----------------------------------------------------------------------------------------

    def step(self, dt: float, sp: setpoint_t, motors_on: bool) -> None:
        """Advance truth and estimate by ``dt`` seconds under setpoint ``sp`` (already supervisor-overridden)."""
        if dt <= 0:
            return
        t, c = self.truth, self.config
        x0, y0 = t.x, t.y
        if not motors_on:
            self._z_integral = 0.0
            if t.z > 0.0:
                t.vz -= GRAVITY * dt
                t.x += t.vx * dt
                t.y += t.vy * dt
                t.z += t.vz * dt
            if t.z <= 0.0:
                t.z, t.vx, t.vy, t.vz = 0.0, 0.0, 0.0, 0.0
        else:
            self._step_wind(dt)
            target = self._horizontal_velocity_target(sp)
            if target is None:  # level: only drag acts
                ax, ay = -t.vx / c.drag_tau_s, -t.vy / c.drag_tau_s
            else:
                # the loop regulates the *estimated* velocity towards the target
                ax = (target[0] - (t.vx + self._vx_err)) / c.velocity_tau_s
                ay = (target[1] - (t.vy + self._vy_err)) / c.velocity_tau_s
                a_max = GRAVITY * math.tan(math.radians(c.tilt_max_deg))
                norm = math.hypot(ax, ay)
                if norm > a_max:
                    ax, ay = ax * a_max / norm, ay * a_max / norm
            ax += self._wind_ax
            ay += self._wind_ay
            vz_target = self._vertical_velocity_target(sp, dt)
            az = (vz_target - t.vz) / c.vertical_tau_s
            t.x += (t.vx + 0.5 * ax * dt) * dt
            t.y += (t.vy + 0.5 * ay * dt) * dt
            t.z = max(0.0, t.z + (t.vz + 0.5 * az * dt) * dt)
            t.vx += ax * dt
            t.vy += ay * dt
            t.vz += az * dt
            self._step_yaw(dt, sp)
        self.distance_flown_m += math.hypot(t.x - x0, t.y - y0)
        self._step_drift(math.hypot(t.x - x0, t.y - y0))
        self._refresh_estimate()

    def _step_yaw(self, dt, sp):
        t = self.truth
        if sp.mode.yaw == 1:
            error = (sp.attitude.yaw - t.yaw + 180.0) % 360.0 - 180.0
            t.yaw += error * min(1.0, dt / self.config.yaw_tau_s)
        elif sp.mode.yaw == 2:
            t.yaw += sp.attitudeRate.yaw * dt
        t.yaw = (t.yaw + 180.0) % 360.0 - 180.0

    def _step_wind(self, dt):
        c = self.config
        if c.wind_gust_mps2 <= 0.0:
            return
        # Ornstein-Uhlenbeck: stationary std wind_gust_mps2, correlation time wind_tau_s
        decay = math.exp(-dt / c.wind_tau_s)
        spread = c.wind_gust_mps2 * math.sqrt(1.0 - decay * decay)
        self._wind_ax = self._wind_ax * decay + spread * self._rng.gauss(0.0, 1.0)
        self._wind_ay = self._wind_ay * decay + spread * self._rng.gauss(0.0, 1.0)

    def _step_drift(self, moved_m):
        c = self.config
        if c.estimator == "flow" and moved_m > 0.0:
            spread = c.flow_drift_per_m * math.sqrt(moved_m)
            self._bias_x += spread * self._rng.gauss(0.0, 1.0)
            self._bias_y += spread * self._rng.gauss(0.0, 1.0)

    def _refresh_estimate(self):
        t, e, c, g = self.truth, self.estimate, self.config, self._rng.gauss
        e.x = t.x + self._bias_x + g(0.0, c.position_noise_m)
        e.y = t.y + self._bias_y + g(0.0, c.position_noise_m)
        e.z = max(0.0, t.z + g(0.0, c.height_noise_m))
        self._vx_err = g(0.0, c.velocity_noise_mps)
        self._vy_err = g(0.0, c.velocity_noise_mps)
        e.vx, e.vy, e.vz = t.vx + self._vx_err, t.vy + self._vy_err, t.vz
        e.yaw = t.yaw
