#include "sil_plant.h"

#include <math.h>
#include <string.h>

#define LIFTOFF_MARGIN 1.0001  /* thrust must beat weight by this factor to leave the ground */

/* Motor positions (x, y) in arm units (the X frame's 45 degree arms) and their yaw reaction sign: the
 * firmware's legacy mixer adds yaw to M1 and M3, and controller_pid negates the yaw output, so M2 and M4
 * are the motors whose reaction turns the body counter-clockwise. */
static const double MOTOR_X[4] = {1.0, -1.0, -1.0, 1.0};
static const double MOTOR_Y[4] = {-1.0, -1.0, 1.0, 1.0};
static const double MOTOR_YAW_SIGN[4] = {-1.0, 1.0, -1.0, 1.0};

void silPlantRotation(const sil_body_t *body, double r[3][3]) {
  const double w = body->quaternion[0], x = body->quaternion[1], y = body->quaternion[2], z = body->quaternion[3];
  r[0][0] = 1 - 2 * (y * y + z * z); r[0][1] = 2 * (x * y - w * z);     r[0][2] = 2 * (x * z + w * y);
  r[1][0] = 2 * (x * y + w * z);     r[1][1] = 1 - 2 * (x * x + z * z); r[1][2] = 2 * (y * z - w * x);
  r[2][0] = 2 * (x * z - w * y);     r[2][1] = 2 * (y * z + w * x);     r[2][2] = 1 - 2 * (x * x + y * y);
}

void silPlantEuler(const sil_body_t *body, double *roll_deg, double *pitch_deg, double *yaw_deg) {
  const double w = body->quaternion[0], x = body->quaternion[1], y = body->quaternion[2], z = body->quaternion[3];
  const double to_deg = 180.0 / M_PI;
  double sin_pitch = 2 * (w * y - z * x);
  sin_pitch = sin_pitch > 1 ? 1 : (sin_pitch < -1 ? -1 : sin_pitch);
  *roll_deg = atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y)) * to_deg;
  /* the firmware's stateEstimate.pitch has the legacy sign: positive is nose up */
  *pitch_deg = -asin(sin_pitch) * to_deg;
  *yaw_deg = atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)) * to_deg;
}

void silPlantInit(sil_body_t *body, const sil_config_t *config) {
  memset(body, 0, sizeof(*body));
  for (int i = 0; i < 3; i++) {
    body->position[i] = config->start[i];
  }
  const double half_yaw = 0.5 * config->start_yaw_deg * M_PI / 180.0;
  body->quaternion[0] = cos(half_yaw);
  body->quaternion[3] = sin(half_yaw);
  body->battery_v = config->battery_full_v;
  body->on_ground = body->position[2] <= 0.0;
  body->acceleration[2] = 0.0;
}

void silPlantSetMotors(sil_body_t *body, const double ratio[4]) {
  for (int i = 0; i < 4; i++) {
    body->motor_command[i] = ratio[i] < 0 ? 0 : (ratio[i] > 1 ? 1 : ratio[i]);
  }
}

static void stepMotors(sil_body_t *body, const sil_config_t *c, double dt) {
  const double blend = 1.0 - exp(-dt / c->motor_tau_s);
  const double voltage_ratio = body->battery_v / c->reference_v;
  for (int i = 0; i < 4; i++) {
    const double target = body->motor_command[i] * voltage_ratio;
    body->motor_speed[i] += (target - body->motor_speed[i]) * blend;
    body->thrust[i] = c->thrust_max_n * body->motor_speed[i] * body->motor_speed[i];
  }
}

/* Open-circuit voltage falls linearly with the charge used; the load draws it down through the internal
 * resistance. The current scales with thrust^1.5 (momentum theory: induced power). */
static void stepBattery(sil_body_t *body, const sil_config_t *c, double dt) {
  const double hover_thrust = c->mass_kg * SIL_GRAVITY;
  double total = 0.0;
  for (int i = 0; i < 4; i++) {
    total += body->thrust[i];
  }
  const double load = total > 0 ? pow(total / hover_thrust, 1.5) : 0.0;
  const double current = c->hover_current_a * load;
  body->consumed_mah += current * dt / 3.6;
  double used = body->consumed_mah / c->battery_capacity_mah;
  used = used > 1 ? 1 : used;
  const double open_circuit = c->battery_full_v - (c->battery_full_v - c->battery_empty_v) * used;
  body->battery_v = open_circuit - current * c->battery_resistance_ohm;
}

static void stepWind(sil_body_t *body, const sil_config_t *c, sil_random_t *rng, double dt) {
  if (c->wind_gust_mps2 <= 0.0) {
    return;
  }
  const double decay = exp(-dt / c->wind_tau_s);
  const double spread = c->wind_gust_mps2 * sqrt(1.0 - decay * decay);
  for (int i = 0; i < 2; i++) {
    body->wind_acceleration[i] = body->wind_acceleration[i] * decay + silRandomGauss(rng, spread);
  }
}

static void bodyTorque(const sil_body_t *body, const sil_config_t *c, double torque[3]) {
  const double arm = c->arm_m * M_SQRT1_2;
  torque[0] = torque[1] = torque[2] = 0.0;
  for (int i = 0; i < 4; i++) {
    torque[0] += MOTOR_Y[i] * arm * body->thrust[i];
    torque[1] -= MOTOR_X[i] * arm * body->thrust[i];
    torque[2] += MOTOR_YAW_SIGN[i] * c->torque_per_thrust_m * body->thrust[i];
  }
  for (int i = 0; i < 3; i++) {
    torque[i] -= c->angular_drag_nm_per_radps * body->rates[i];
  }
}

static void integrateAttitude(sil_body_t *body, const sil_config_t *c, double dt) {
  double torque[3];
  bodyTorque(body, c, torque);
  const double *inertia = c->inertia_kg_m2;
  const double *w = body->rates;
  /* Euler's equations: I w' = torque - w x (I w) */
  const double iw[3] = {inertia[0] * w[0], inertia[1] * w[1], inertia[2] * w[2]};
  const double gyroscopic[3] = {w[1] * iw[2] - w[2] * iw[1], w[2] * iw[0] - w[0] * iw[2], w[0] * iw[1] - w[1] * iw[0]};
  for (int i = 0; i < 3; i++) {
    body->rates[i] += (torque[i] - gyroscopic[i]) / inertia[i] * dt;
  }
  double *q = body->quaternion;
  const double half = 0.5 * dt;
  const double dq[4] = {
    -half * (q[1] * w[0] + q[2] * w[1] + q[3] * w[2]),
    half * (q[0] * w[0] + q[2] * w[2] - q[3] * w[1]),
    half * (q[0] * w[1] - q[1] * w[2] + q[3] * w[0]),
    half * (q[0] * w[2] + q[1] * w[1] - q[2] * w[0]),
  };
  double norm = 0.0;
  for (int i = 0; i < 4; i++) {
    q[i] += dq[i];
    norm += q[i] * q[i];
  }
  norm = sqrt(norm);
  for (int i = 0; i < 4; i++) {
    q[i] /= norm;
  }
}

/* Resting on the ground: level, still, yaw kept (the legs hold it). */
static void restOnGround(sil_body_t *body) {
  const double yaw = atan2(2 * (body->quaternion[0] * body->quaternion[3] + body->quaternion[1] * body->quaternion[2]),
                           1 - 2 * (body->quaternion[2] * body->quaternion[2] + body->quaternion[3] * body->quaternion[3]));
  body->quaternion[0] = cos(0.5 * yaw);
  body->quaternion[1] = body->quaternion[2] = 0.0;
  body->quaternion[3] = sin(0.5 * yaw);
  body->position[2] = 0.0;
  for (int i = 0; i < 3; i++) {
    body->velocity[i] = 0.0;
    body->rates[i] = 0.0;
    body->acceleration[i] = 0.0;
  }
  body->on_ground = true;
}

void silPlantStep(sil_body_t *body, const sil_config_t *c, sil_random_t *wind_rng, double dt) {
  stepMotors(body, c, dt);
  stepBattery(body, c, dt);
  if (body->crashed != SIL_CRASH_NONE) {
    return;  /* a crashed MAV lies where it fell */
  }
  stepWind(body, c, wind_rng, dt);
  double r[3][3];
  silPlantRotation(body, r);
  double total_thrust = 0.0;
  for (int i = 0; i < 4; i++) {
    total_thrust += body->thrust[i];
  }
  const double weight = c->mass_kg * SIL_GRAVITY;
  if (body->on_ground && total_thrust * r[2][2] <= weight * LIFTOFF_MARGIN) {
    restOnGround(body);
    return;
  }
  body->on_ground = false;
  double force[3];
  for (int i = 0; i < 3; i++) {
    force[i] = r[i][2] * total_thrust - c->drag_n_per_mps[i] * body->velocity[i];
  }
  force[0] += c->mass_kg * body->wind_acceleration[0];
  force[1] += c->mass_kg * body->wind_acceleration[1];
  force[2] -= weight;
  for (int i = 0; i < 3; i++) {
    body->acceleration[i] = force[i] / c->mass_kg;
    body->velocity[i] += body->acceleration[i] * dt;
    body->position[i] += body->velocity[i] * dt;
  }
  integrateAttitude(body, c, dt);
  silPlantRotation(body, r);
  if (r[2][2] < 0.0) {
    body->crashed = SIL_CRASH_TUMBLE;
  }
  if (body->position[2] <= 0.0) {
    if (body->velocity[2] < -SIL_CRASH_SPEED_MPS) {
      body->crashed = SIL_CRASH_GROUND_HIT;
    }
    restOnGround(body);
  }
}
