/*
 * The visual servo (crazyflie_app/app/visual_servo.py): the servo law, the pixel filter's prediction, the relaxed
 * reached rule and the bounded integral.
 */
#include <math.h>

#include "nav_internal.h"

void navServoVelocity(double offset_fwd_m, double offset_left_m, double gain, double max_speed,
                      const double integral[2], double integral_gain, double* vx, double* vy) {
  *vx = gain * offset_fwd_m + integral_gain * integral[0];
  *vy = gain * offset_left_m + integral_gain * integral[1];
  const double speed = hypot(*vx, *vy);
  if (speed > max_speed && max_speed > 0.0) {
    *vx = *vx * max_speed / speed;
    *vy = *vy * max_speed / speed;
  }
}

void navPredictFilter(NavCore* core, int32_t t_ms) {
  if (t_ms > core->filter_t_ms) {
    navKalmanPredict(&core->filter, (double)(t_ms - core->filter_t_ms) / 1000.0); /* real time, s */
    core->filter_t_ms = t_ms;
  }
}

void navSettleThresholds(const NavCore* core, int32_t t_ms, double* radius, double* speed) {
  const NavParams* p = &core->params;
  if (!core->has_captured_since) {
    *radius = p->settle_radius_px;
    *speed = p->settle_speed;
    return;
  }
  const double relax_s = maxd(0.0, (double)(t_ms - core->captured_since - p->settle_grace_ms) / 1000.0);
  *radius = mind(p->settle_radius_px + p->settle_relax * relax_s, p->capture_radius_px);
  *speed = p->settle_speed * *radius / maxd(p->settle_radius_px, 1e-9);
}

void navIntegrateServo(NavCore* core, int32_t t_ms, const double offset[2], double error_px, double speed) {
  const NavParams* p = &core->params;
  if (error_px > p->servo_integral_band * p->settle_radius_px || p->servo_integral <= 0.0) {
    core->servo_integral[0] = core->servo_integral[1] = 0.0;
    return;
  }
  if (speed >= p->settle_speed) {
    return; /* still moving: hold the integral */
  }
  const double dt = !core->has_last_tick ? 0.0 : maxd(0.0, (double)(t_ms - core->last_tick) / 1000.0);
  double ix = core->servo_integral[0] + offset[0] * dt, iy = core->servo_integral[1] + offset[1] * dt;
  const double limit = 0.5 * p->approach_speed / p->servo_integral;
  const double norm = hypot(ix, iy);
  if (norm > limit) {
    ix = ix * limit / norm;
    iy = iy * limit / norm;
  }
  core->servo_integral[0] = ix;
  core->servo_integral[1] = iy;
}
