/* A rigid-body quadrotor: 6 degrees of freedom, four motors with lag, a sagging 2S battery, ground
 * contact, wind gusts as forces, and the crash rule (tilt past 90 degrees, or the ground hit faster than
 * SIL_CRASH_SPEED_MPS). World frame: x forward, y left, z up; body frame FLU; motors in the Crazyflie's
 * X layout (M1 front right, M2 back right, M3 back left, M4 front left). */
#pragma once
#include <stdbool.h>

#include "sil_api.h"
#include "sil_random.h"

#define SIL_GRAVITY 9.81
/* What a Crazyflie survives hitting the ground with. A motor-cut landing is routine: cflib's MotionCommander
 * cuts the motors a few cm up (the issue measured 7 cm, 1.2 m/s; a cut at 15 cm hits at sqrt(2 g h) = 1.7 m/s),
 * while a fall from 1 m hits at 4.4 m/s and is a crash. 2.5 m/s is a free fall from 0.32 m: between the two,
 * above every landing (both apps and cflib's land calls touch down below 1.8 m/s on this plant). Tumbling (a
 * flip) stays a crash whatever the speed, as the firmware's supervisor has it (docs/firmware-plant.md). */
#define SIL_CRASH_SPEED_MPS 2.5

typedef struct {
  double position[3];
  double velocity[3];
  double quaternion[4];         /* w, x, y, z: body to world */
  double rates[3];              /* body rad/s */
  double acceleration[3];       /* world, of the last step (for the IMU) */
  double motor_speed[4];        /* normalised: 1 = full command at the reference voltage */
  double motor_command[4];      /* 0..1 */
  double thrust[4];             /* N */
  double battery_v;
  double consumed_mah;
  double wind_acceleration[2];
  bool on_ground;
  int crashed;                  /* SIL_CRASH_* */
} sil_body_t;

void silPlantInit(sil_body_t *body, const sil_config_t *config);
void silPlantSetMotors(sil_body_t *body, const double ratio[4]);
void silPlantStep(sil_body_t *body, const sil_config_t *config, sil_random_t *wind_rng, double dt);
/* body-to-world rotation matrix of the current attitude */
void silPlantRotation(const sil_body_t *body, double r[3][3]);
void silPlantEuler(const sil_body_t *body, double *roll_deg, double *pitch_deg, double *yaw_deg);
